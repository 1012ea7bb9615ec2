// libFuzzer target: the checks load_mesh() runs on a mesh file before Assimp sees it (PLY and OFF
// counts, list lengths and face indices, binary STL triangle counts), on arbitrary bytes written
// to a private temporary file. The first byte picks the file's name (.ply, .off, .stl or .obj:
// the STL check depends on it); the rest is the file. A file the checks refuse must throw
// esf::IoError; anything else (a crash, a sanitizer report, another exception, a huge allocation,
// a time-out) is a bug. Assimp itself is not run: it is not built with the sanitizers.
#include <array>
#include <cstddef>
#include <cstdint>

#include "esf/core/error.hpp"
#include "fuzz_input.hpp"
#include "mesh/mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    static constexpr std::array<const char*, 4> kNames = {"fuzz.ply", "fuzz.off", "fuzz.stl",
                                                          "fuzz.obj"};
    const esf::fuzz::TempFile file(kNames[data[0] % kNames.size()],
                                   esf::fuzz::bytes_of(data + 1, size - 1));
    try {
        esf::detail::check_mesh_file(file.path(), size - 1);
    } catch (const esf::IoError&) {
    }
    return 0;
}
