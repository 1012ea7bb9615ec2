// libFuzzer target: esf::read_catalog (which reads a path) on arbitrary bytes written to a
// private temporary file; malformed input must throw esf::IoError.
#include <cstddef>
#include <cstdint>

#include "esf/core/error.hpp"
#include "esf/training/training.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const esf::fuzz::TempFile file("catalog.csv", esf::fuzz::bytes_of(data, size));
    try {
        const esf::Catalog catalog = esf::read_catalog(file.path());
        for (const esf::CatalogEntry& entry : catalog.entries) {
            if (entry.file.empty()) __builtin_trap();
            (void)esf::typical_extent(catalog, entry.category);
        }
    } catch (const esf::IoError&) {
    }
    return 0;
}
