#pragma once
// The checks made on a mesh file before Assimp reads it (mesh_checks.cpp): the importer helper
// runs them all (mesh_import.cpp); load_mesh() runs mesh_file_size() itself before it starts the
// helper; the fuzz target fuzz/mesh_fuzz.cpp runs check_mesh_file().

#include <cstdint>
#include <string>

namespace esf::detail {

/// The size of the mesh file `path`; throws esf::IoError naming it when it does not exist, is a
/// directory, is empty or is not a regular file (a FIFO, a device). Opens nothing.
std::uintmax_t mesh_file_size(const std::string& path);

/// Throws esf::IoError naming `path` when the file (of `file_size` bytes) is one Assimp 5.2 must
/// not see: a PLY header without end_header, PLY element counts or list lengths beyond the bytes
/// present, OFF counts beyond the file size, OFF faces missing or naming a vertex that does not
/// exist, or a binary STL whose triangle count does not match the file size. Returns for any other
/// file (Assimp reports what it cannot read).
void check_mesh_file(const std::string& path, std::uintmax_t file_size);

}  // namespace esf::detail
