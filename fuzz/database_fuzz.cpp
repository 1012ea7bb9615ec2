// libFuzzer target: the database opener and its readers on arbitrary bytes written to a private
// temporary file, opened read-only. A corrupt or foreign file must throw esf::IoError (or
// std::invalid_argument from a reader that finds no usable descriptor kind).
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "esf/core/error.hpp"
#include "esf/training/database.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const esf::fuzz::TempFile file("fuzz.sqlite", esf::fuzz::bytes_of(data, size));
    try {
        const esf::Database db(file.path(), esf::OpenMode::kRead);
        (void)db.settings();
        (void)db.summary();
        for (const esf::DescriptorKind& kind : db.descriptor_kinds()) {
            (void)db.weights(kind.name);
            const esf::DescriptorMatrix matrix = db.load_descriptors(kind.name);
            // row(i) reads rows() x dimension floats: the loader must hold that many.
            if (matrix.kind.dimension < 0 ||
                matrix.data.size() !=
                    matrix.rows() * static_cast<std::size_t>(matrix.kind.dimension))
                __builtin_trap();
        }
        for (const esf::ModelInfo& model : db.models()) (void)db.views(model.category, model.name);
    } catch (const esf::IoError&) {
    } catch (const std::invalid_argument&) {
    }
    return 0;
}
