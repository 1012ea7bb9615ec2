// esf info DB : what a training database holds (categories, models, views, settings).

#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <variant>

#include "cli_common.hpp"
#include "commands.hpp"
#include "esf/training/database.hpp"

namespace esf::cli {

namespace {

struct InfoArgs {
    std::string database;
    bool json = false;
    bool models = false;
};

nlohmann::json to_json(const SettingValue& value) {
    return std::visit([](const auto& v) { return nlohmann::json(v); }, value);
}

void print_json(const InfoArgs& args, const Database& db, const DatabaseSummary& s) {
    nlohmann::json out;
    out["database"] = args.database;
    out["models"] = s.models;
    out["failed_models"] = s.failed_models;
    out["views"] = s.views;
    out["skipped_views"] = s.skipped_views;
    out["surfaces"] = s.surfaces;
    out["categories"] = nlohmann::json::object();
    out["category_views"] = nlohmann::json::object();
    for (const auto& c : s.categories) {
        out["categories"][c.name] = c.models;
        out["category_views"][c.name] = c.views;
    }
    out["descriptors"] = nlohmann::json::array();
    for (const auto& k : s.descriptor_kinds) {
        const auto w = db.weights(k.name);
        out["descriptors"].push_back({{"name", k.name},
                                      {"version", k.version},
                                      {"dimension", k.dimension},
                                      {"weights", w ? nlohmann::json(*w) : nlohmann::json()}});
    }
    out["settings"] = nlohmann::json::object();
    for (const auto& [key, value] : db.settings()) out["settings"][key] = to_json(value);
    out["failed"] = nlohmann::json::array();
    if (args.models) out["model_list"] = nlohmann::json::array();
    for (const auto& m : db.models()) {
        if (m.status == ModelStatus::kFailed)
            out["failed"].push_back({{"model", m.category + "/" + m.name}, {"error", m.error}});
        if (args.models)
            out["model_list"].push_back({{"category", m.category},
                                         {"name", m.name},
                                         {"file", m.file},
                                         {"group", m.group},
                                         {"scale", m.scale},
                                         {"status", to_string(m.status)},
                                         {"views", m.views},
                                         {"skipped_views", m.skipped_views}});
    }
    std::cout << out.dump(2) << '\n';
}

void print_text(const InfoArgs& args, const Database& db, const DatabaseSummary& s) {
    std::printf("%s: %zu models in %zu categories, %zu views (%zu skipped)", args.database.c_str(),
                s.models, s.categories.size(), s.views, s.skipped_views);
    if (s.failed_models) std::printf(", %zu failed models", s.failed_models);
    std::printf("\n");
    if (s.surfaces == s.models)
        std::printf("model surfaces: stored (recognition verifies its hypotheses)\n");
    else
        std::printf(
            "model surfaces: %zu of %zu models (recognition verifies only with "
            "--verify-meshes ROOT; train again to store them)\n",
            s.surfaces, s.models);
    for (const auto& k : s.descriptor_kinds)
        std::printf("descriptor: %s version %d, %d floats, weights: %s\n", k.name.c_str(),
                    k.version, k.dimension,
                    db.weights_are_stale(k.name) ? "stale (ignored; learn them again)"
                    : db.weights(k.name)         ? "learned"
                                                 : "none");

    std::printf("\n%-20s %7s %7s %8s\n", "category", "models", "views", "skipped");
    for (const auto& c : s.categories) {
        std::printf("%-20s %7zu %7zu %8zu", c.name.c_str(), c.models, c.views, c.skipped_views);
        if (c.failed_models) std::printf("  (%zu failed)", c.failed_models);
        std::printf("\n");
    }

    std::printf("\nsettings:\n");
    for (const auto& [key, value] : db.settings())
        std::printf("  %-28s %s\n", key.c_str(), to_string(value).c_str());

    const auto models = db.models();
    if (args.models) {
        std::printf("\n%-40s %-28s %8s %6s %8s\n", "model", "group", "scale", "views", "skipped");
        for (const auto& m : models) {
            const std::string name = m.category + "/" + m.name;
            std::printf("%-40s %-28s %8.4g %6zu %8zu%s\n", name.c_str(), m.group.c_str(), m.scale,
                        m.views, m.skipped_views,
                        m.status == ModelStatus::kFailed ? "  FAILED" : "");
        }
    }
    bool header = false;
    for (const auto& m : models) {
        if (m.status != ModelStatus::kFailed) continue;
        if (!header) std::printf("\nfailed models:\n");
        header = true;
        std::printf("  %s/%s: %s\n", m.category.c_str(), m.name.c_str(), m.error.c_str());
    }
}

void run_info(const InfoArgs& args) {
    const Database db(args.database, OpenMode::kRead);
    const DatabaseSummary summary = db.summary();
    if (args.json)
        print_json(args, db, summary);
    else
        print_text(args, db, summary);
}

}  // namespace

void add_info_command(CLI::App& app) {
    auto args = std::make_shared<InfoArgs>();
    CLI::App* cmd = add_command(
        app, "info", "Show what a training database holds and how it was trained",
        "Show what a training database holds: categories, models per category, views,\n"
        "skipped views, failed models and the settings it was trained with. Read-only.");
    cmd->add_option("database", args->database, "Database made by esf train")->required();
    cmd->add_flag("--json", args->json,
                  "One JSON object: models, views, skipped_views, categories {name: models}, "
                  "settings, ...");
    cmd->add_flag("--models", args->models, "Also list every model (group, scale, views)");
    cmd->callback([args] { run_info(*args); });
}

}  // namespace esf::cli
