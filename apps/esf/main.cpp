// esf: recognise the category of objects seen by a depth sensor, trained only on CAD models.
// main() wires the subcommands together and turns exceptions into one line on stderr.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>

#include "cli_common.hpp"
#include "commands.hpp"
#include "esf/core/error.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#endif

namespace {

void tune_heap() {
#if defined(__GLIBC__)
    // A batch reads file after file, each needing blocks of several MB (a 640 x 480 scene:
    // the decoded columns, the points, the finite points). glibc would map some of them afresh
    // for every file, or give the top of its heap back to the system and fault it in again (up
    // to 2,400 page faults a scene). Blocks up to 64 MiB come from the heap and up to 256 MiB
    // of freed memory stay in it for the next file; larger blocks are still mapped and unmapped.
    mallopt(M_MMAP_THRESHOLD, 64 << 20);
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
#if defined(MADV_HUGEPAGE)
    // The first 48 MiB of the heap on transparent huge pages where the kernel offers them (as
    // GLIBC_TUNABLES=glibc.malloc.hugetlb=1 would): the descriptor's working memory (the cube
    // table, the lines, the points it samples at random) is then touched in 2 MiB pages, with
    // a few hundred page faults fewer per process and fewer TLB misses (BENCHMARKS.md). The
    // block is only reserved: memory is used where it is touched, as before.
    constexpr std::size_t kHugeHeap = std::size_t{48} << 20, kHugePage = std::size_t{2} << 20;
    if (void* block = std::malloc(kHugeHeap)) {
        const auto at = reinterpret_cast<std::uintptr_t>(block);
        const std::uintptr_t begin = (at + kHugePage - 1) & ~(kHugePage - 1);
        const std::uintptr_t end = (at + kHugeHeap) & ~(kHugePage - 1);
        if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
        std::free(block);
    }
#endif
#endif
}

}  // namespace

int main(int argc, char** argv) {
    tune_heap();
    CLI::App app{
        "esf - 3-D object classification with the Ensemble of Shape Functions descriptor\n"
        "(Wohlkinger & Vincze, 2011). Train on CAD models, recognise objects in depth data."};
    app.require_subcommand(1);
    app.set_version_flag("--version", "esf 0.1.0");
    esf::cli::add_demo_command(app);
    esf::cli::add_describe_command(app);
    esf::cli::add_train_command(app);
    esf::cli::add_info_command(app);
    esf::cli::add_segment_command(app);
    esf::cli::add_generate_command(app);
    esf::cli::add_render_command(app);
    esf::cli::add_classify_command(app);
    esf::cli::add_scene_command(app);
    esf::cli::add_compare_command(app);
    esf::cli::add_eval_command(app);
    esf::cli::add_learn_weights_command(app);
    esf::cli::add_generate_scenes_command(app);
    esf::cli::add_live_command(app);
    esf::cli::add_record_scenes_command(app);
    // @commands: one add_<name>_command(app) call per command above this line
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);  // --help and --version, on stdout
        // A usage error is one line like every other error: CLI11's message on one line,
        // without its "Run with --help" footer.
        std::string message = e.what();
        if (app.get_subcommands().empty() && argc > 1 && argv[1][0] != '-') {
            message = std::string("unknown command '") + argv[1] + "' (see esf --help)";
        }
        std::replace(message.begin(), message.end(), '\n', ' ');
        while (!message.empty() && message.back() == ' ') message.pop_back();
        std::fprintf(stderr, "esf: error: %s\n", message.c_str());
        return esf::cli::kExitUsage;
    } catch (const esf::cli::ExitStatus& status) {
        return status.code;
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "esf: error: %s\n", e.what());
        return esf::cli::kExitRuntime;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "esf: error: %s\n", e.what());
        return esf::cli::kExitRuntime;
    }
    return 0;
}
