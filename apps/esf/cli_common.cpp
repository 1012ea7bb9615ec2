#include "cli_common.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <limits>
#include <string>

#include "esf/core/parallel.hpp"
#include "esf/training/database.hpp"

namespace esf::cli {

void warn_if_weights_stale(const std::string& database, const std::string& descriptor) {
    const Database db(database, OpenMode::kRead);
    if (db.weights_are_stale(descriptor))
        std::fprintf(stderr,
                     "esf: warning: %s: the learned weights predate the database's last "
                     "training and are ignored; run esf learn-weights again\n",
                     database.c_str());
}

namespace {
double now_seconds() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}
}  // namespace

bool stderr_is_terminal() { return isatty(fileno(stderr)) != 0; }

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(total),
      enabled_(stderr_is_terminal()),
      start_(now_seconds()) {}

Progress::~Progress() { finish(); }

void Progress::update(std::size_t done, const std::string& detail) {
    if (!enabled_ || finished_) return;
    const double t = now_seconds();
    if (done < total_ && t - last_draw_ < 0.1) return;
    last_draw_ = t;
    const double elapsed = t - start_;
    const double fraction = total_ ? static_cast<double>(done) / static_cast<double>(total_) : 1.0;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar.resize(kWidth, '.');
    const double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(stderr, "\r%s [%s] %zu/%zu %s ETA %.0fs   ", label_.c_str(), bar.c_str(), done,
                 total_, detail.c_str(), eta);
    std::fflush(stderr);
}

void Progress::finish() {
    if (!enabled_ || finished_) return;
    finished_ = true;
    std::fprintf(stderr, "\n");
}

namespace {

/// For --threads: see add_threads_option().
CLI::Validator thread_limit() {
    return CLI::Validator(
        [](std::string& value) -> std::string {
            int threads = 0;
            try {
                std::size_t used = 0;
                threads = std::stoi(value, &used);
                if (used != value.size()) throw std::invalid_argument(value);
            } catch (const std::out_of_range&) {
                threads = std::numeric_limits<int>::max();  // a huge count: capped below
                if (!value.empty() && value[0] == '-') return "must be >= 0 (0 = all cores)";
            } catch (const std::invalid_argument&) {
                return "not a whole number of threads";
            }
            if (threads < 0) return "must be >= 0 (0 = all cores), got " + value;
            if (threads <= esf::kThreadsWithinAnyLimit) return {};
            const int limit = esf::max_threads();
            if (threads > limit) {
                std::fprintf(
                    stderr, "esf: warning: --threads %s is above 4 x the %d cores; using %d\n",
                    value.size() > 12 ? "(a huge count)" : value.c_str(), limit / 4, limit);
                value = std::to_string(limit);
            }
            return {};
        },
        "THREADS", "thread_limit");
}

/// For --seed: see add_seed_option().
CLI::Validator non_negative_seed() {
    return CLI::Validator(
        [](std::string& value) -> std::string {
            const std::size_t first = value.find_first_not_of(" \t");
            if (first != std::string::npos && value[first] == '-')
                return "seed must be a non-negative integer, got " + value;
            return {};
        },
        "SEED", "non_negative_seed");
}

CLI::Validator fold_text() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            esf::GroupSelection selection;
            try {
                parse_fold(text, selection);
            } catch (const std::invalid_argument& e) {
                return e.what();
            }
            return {};
        },
        "K/N");
}

}  // namespace

CLI::App* add_command(CLI::App& app, const std::string& name, const std::string& summary,
                      const std::string& details) {
    CLI::App* cmd = app.add_subcommand(name, summary);
    cmd->footer(details);
    return cmd;
}

CLI::Option* add_threads_option(CLI::App& cmd, int& threads) {
    return cmd.add_option("--threads", threads, "Worker threads, 0 = all cores")
        ->transform(thread_limit())
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
}

CLI::Option* add_seed_option(CLI::App& cmd, std::uint64_t& seed, const std::string& what) {
    return cmd.add_option("--seed", seed, what)->check(non_negative_seed())->capture_default_str();
}

void add_catalog_options(CLI::App& cmd, std::string& catalog, bool& no_catalog) {
    auto* file =
        cmd.add_option("--catalog", catalog, "Catalog CSV (default: ROOT/catalog.csv when present)")
            ->check(CLI::ExistingFile);
    cmd.add_flag("--no-catalog", no_catalog,
                 "Ignore any catalog: all models metric, each its own group")
        ->excludes(file);
}

void GroupOptions::add_to(CLI::App& cmd) {
    cmd.add_option("--groups", only_, "Only the models of these catalog groups (comma-separated)")
        ->delimiter(',');
    cmd.add_option("--exclude-groups", except_,
                   "Not the models of these catalog groups (comma-separated)")
        ->delimiter(',');
    cmd.add_option("--categories", categories_,
                   "Only the models of these categories (comma-separated; folds as without it)")
        ->delimiter(',');
    auto* fold =
        cmd.add_option(
               "--fold", fold_,
               "K/N: only the groups of fold K of N (each category's groups dealt into N folds; a "
               "category with one group is in none)")
            ->check(fold_text());
    cmd.add_option("--other-folds", other_folds_,
                   "K/N: every group but those of fold K of N (train on these, generate or "
                   "evaluate on --fold K/N)")
        ->check(fold_text())
        ->excludes(fold);
}

esf::GroupSelection GroupOptions::selection() const {
    esf::GroupSelection selection;
    selection.only = only_;
    selection.except = except_;
    selection.categories = categories_;
    if (!fold_.empty()) parse_fold(fold_, selection);
    if (!other_folds_.empty()) {
        parse_fold(other_folds_, selection);
        selection.other_folds = true;
    }
    return selection;
}

}  // namespace esf::cli
