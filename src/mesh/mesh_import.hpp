#pragma once
// Internal: mesh import in a helper process. Assimp recurses, loops or allocates as a hostile
// file leads it (a Collada file whose nodes instance each other overflows the stack), so
// load_mesh() runs it in `esf_mesh_import`, a small executable started with posix_spawn
// (child_process.hpp), and only that executable links Assimp. A crash, a hang or a memory
// blow-up there is one esf::IoError for that file.
//
// Command line: esf_mesh_import ADDRESS_SPACE_MIB SECONDS PATH
//   The helper limits its own address space (RLIMIT_AS, ADDRESS_SPACE_MIB MiB; not in a build
//   with AddressSanitizer, which reserves terabytes) and CPU time (RLIMIT_CPU, SECONDS rounded
//   up, plus 1); load_mesh() kills it with SIGKILL after SECONDS of wall time.
// Reply on its stdout, native byte order, then exit status 0:
//   u64 status | u64 a | u64 b | payload
//   status 0 (a mesh): a vertices, b triangles; a x (f32 x, f32 y, f32 z), b x (i32 x 3)
//   status 1 (esf::IoError) or 2 (std::invalid_argument): a bytes of message (what()), b = 0
// Other exit statuses: 2 bad command line, 3 the reply could not be written, 4 an allocation
// failed (the address-space limit); a signal: a crash (SIGSEGV, SIGABRT), SIGXCPU: the CPU limit.

#include <cstdint>
#include <string>

#include "esf/mesh/mesh.hpp"

namespace esf::detail {

/// Reply statuses.
inline constexpr std::uint64_t kMeshReplyOk = 0;
inline constexpr std::uint64_t kMeshReplyIoError = 1;
inline constexpr std::uint64_t kMeshReplyInvalidArgument = 2;
/// Exit statuses of the helper besides 0.
inline constexpr int kMeshImportUsage = 2;
inline constexpr int kMeshImportWriteFailed = 3;
inline constexpr int kMeshImportOutOfMemory = 4;
/// The helper's file name (in lib/esf/ when installed, lib/ of the build tree).
inline constexpr const char* kMeshImporterFile = "esf_mesh_import";

/// The import itself, in this process (the helper's work): the checks of mesh_checks.hpp, then
/// Assimp, as documented at load_mesh().
Mesh import_mesh(const std::string& path);

}  // namespace esf::detail
