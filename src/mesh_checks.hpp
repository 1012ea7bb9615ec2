#pragma once
// The checks load_mesh() runs on a mesh file before Assimp reads it (mesh.cpp), declared for the
// fuzz target fuzz/mesh_fuzz.cpp.

#include <cstdint>
#include <string>

namespace esf::detail {

/// Throws esf::IoError naming `path` when the file (of `file_size` bytes) is one Assimp 5.2 must
/// not see: a PLY header without end_header, PLY element counts or list lengths beyond the bytes
/// present, OFF counts beyond the file size, OFF faces missing or naming a vertex that does not
/// exist, or a binary STL whose triangle count does not match the file size. Returns for any other
/// file (Assimp reports what it cannot read).
void check_mesh_file(const std::string& path, std::uintmax_t file_size);

}  // namespace esf::detail
