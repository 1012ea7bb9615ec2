#pragma once
// Internal: where the files esf installs beside its libraries (lib/esf/: the baselines module,
// the mesh importer helper) lie, seen from code linked into any program or module.

#include <string>
#include <vector>

namespace esf::detail {

/// The places to look for `file`, in order. When the environment variable `env` is set (and not
/// empty), its value only: an explicit choice is the only one tried. Else, with DIR the folder of
/// the binary this code is linked into (program or shared object): DIR/../lib/esf/FILE (an
/// installed program), DIR/FILE, then `build_path` (the build tree's copy) and `install_path`
/// (the configured install prefix), each skipped when empty.
std::vector<std::string> installed_file_candidates(const char* env, const std::string& file,
                                                   const char* build_path,
                                                   const char* install_path);

}  // namespace esf::detail
