// libFuzzer target: esf::read_scene_set on arbitrary bytes; malformed input must throw
// esf::IoError.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "esf/core/error.hpp"
#include "esf/evaluation/scene_evaluation.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::istringstream in(std::string(esf::fuzz::bytes_of(data, size)));
    try {
        const esf::SceneSet set = esf::read_scene_set(in, "/fuzz/scenes.csv");
        for (const esf::LabelledScene& scene : set.scenes)
            for (const esf::SceneObjectLabel& object : scene.objects)
                if (object.class_name.empty()) __builtin_trap();
    } catch (const esf::IoError&) {
    }
    return 0;
}
