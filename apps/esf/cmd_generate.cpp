// esf generate -o DIR : procedural training meshes of the ten Cat10 categories, written as
// DIR/<category>/<model>.ply (an embedded default for `esf train`, nothing to download).

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "esf/shapes/shape_generator.hpp"

namespace esf::cli {

namespace {

struct GenerateArgs {
    std::string output;
    int per_class = 10;
    std::uint64_t seed = 0;
    std::vector<std::string> categories;
    int threads = 0;
    bool json = false;
};

void print_json(const GenerateArgs& args, const std::vector<GeneratedFile>& files) {
    nlohmann::json out;
    out["output"] = args.output;
    out["seed"] = args.seed;
    out["per_class"] = args.per_class;
    out["models"] = nlohmann::json::array();
    for (const GeneratedFile& f : files)
        out["models"].push_back({{"category", f.category},
                                 {"name", f.name},
                                 {"path", f.path},
                                 {"vertices", f.vertices},
                                 {"triangles", f.triangles},
                                 {"extent_m", {f.extent.x(), f.extent.y(), f.extent.z()}}});
    std::cout << out.dump(2) << '\n';
}

void print_text(const GenerateArgs& args, const std::vector<GeneratedFile>& files) {
    struct Range {
        std::size_t models = 0, min_tri = SIZE_MAX, max_tri = 0;
        float min_len = 1e9f, max_len = 0.0f, min_h = 1e9f, max_h = 0.0f;
    };
    std::vector<std::string> order;
    std::map<std::string, Range> ranges;
    for (const GeneratedFile& f : files) {
        if (!ranges.count(f.category)) order.push_back(f.category);
        Range& r = ranges[f.category];
        ++r.models;
        r.min_tri = std::min(r.min_tri, f.triangles);
        r.max_tri = std::max(r.max_tri, f.triangles);
        r.min_len = std::min(r.min_len, f.extent.maxCoeff());
        r.max_len = std::max(r.max_len, f.extent.maxCoeff());
        r.min_h = std::min(r.min_h, f.extent.z());
        r.max_h = std::max(r.max_h, f.extent.z());
    }
    std::printf("esf generate: %zu models (%zu categories x %d, seed %llu) in %s\n", files.size(),
                order.size(), args.per_class, static_cast<unsigned long long>(args.seed),
                args.output.c_str());
    std::printf("%-14s %6s %15s %18s %14s\n", "category", "models", "triangles",
                "longest side (cm)", "height (cm)");
    for (const std::string& c : order) {
        const Range& r = ranges[c];
        std::printf("%-14s %6zu %7zu-%-7zu %8.1f-%-9.1f %6.1f-%-7.1f\n", c.c_str(), r.models,
                    r.min_tri, r.max_tri, 100.0 * r.min_len, 100.0 * r.max_len, 100.0 * r.min_h,
                    100.0 * r.max_h);
    }
}

void run_generate(const GenerateArgs& args) {
    GeneratorOptions options;
    options.per_class = args.per_class;
    options.seed = args.seed;
    options.categories = args.categories;
    options.threads = args.threads;
    std::unique_ptr<Progress> bar;
    const std::vector<GeneratedFile> files =
        write_dataset(args.output, options, [&](std::size_t done, std::size_t total) {
            if (!bar) bar = std::make_unique<Progress>("generate", total);
            bar->update(done);
        });
    if (bar) bar->finish();
    if (args.json)
        print_json(args, files);
    else
        print_text(args, files);
}

}  // namespace

void add_generate_command(CLI::App& app) {
    auto args = std::make_shared<GenerateArgs>();
    std::string known;
    for (const std::string& c : generated_categories()) known += (known.empty() ? "" : ", ") + c;
    CLI::App* cmd = add_command(
        app, "generate", "Write parametric training meshes of the paper's ten categories",
        "Write parametric, randomised training meshes of the paper's ten categories as\n"
        "DIR/<category>/gen_<category>_NNN.ply (binary PLY, metres, +z up, watertight).\n"
        "Categories: " +
            known +
            ";\n"
            "and, only when named, can: wide tins (12-22 cm across, closed, rounded rims, half\n"
            "with a lid), the cans that scanned can sets lack, to add to a database of scans\n"
            "(`esf train DIR -o DB --catalog ../shared/data/meshes/catalog.csv` adds them to a\n"
            "database of the shared meshes).\n"
            "Model i of a category depends only on (seed, category, i): --per-class 5 gives the\n"
            "first 5 models of --per-class 10, whatever the thread count. Train on them with\n"
            "`esf train DIR -o DB`.");
    cmd->add_option("-o,--output", args->output, "Output folder (created; files overwritten)")
        ->required();
    cmd->add_option("--per-class", args->per_class, "Models per category")
        ->capture_default_str()
        ->check(CLI::Range(1, 100000));
    add_seed_option(*cmd, args->seed, "Random seed");
    cmd->add_option("--categories", args->categories,
                    "Comma-separated categories (default: the paper's ten; `can` only when named)")
        ->delimiter(',');
    add_threads_option(*cmd, args->threads);
    cmd->add_flag("--json", args->json,
                  "Print one JSON object: output, seed, per_class, models [{category, name, path, "
                  "vertices, triangles, extent_m}]");
    cmd->callback([args] { run_generate(*args); });
}

}  // namespace esf::cli
