// libFuzzer target: esf::read_test_set on arbitrary bytes; malformed input must throw
// esf::IoError.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "esf/core/error.hpp"
#include "esf/evaluation/evaluation.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::istringstream in(std::string(esf::fuzz::bytes_of(data, size)));
    try {
        const esf::TestSet set = esf::read_test_set(in, "/fuzz/testset.csv");
        for (const esf::TestSample& s : set.samples)
            if (s.file.empty() || s.class_name.empty() || s.line < 2) __builtin_trap();
    } catch (const esf::IoError&) {
    }
    return 0;
}
