#pragma once
// Helpers shared by the esf subcommands: exit codes, errors, progress display.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "esf/core/enum_names.hpp"
#include "esf/training/training.hpp"

namespace esf::cli {

inline constexpr int kExitUsage = 1;
inline constexpr int kExitRuntime = 2;

/// Thrown by a command to end with an exit code after it has printed its own diagnostics
/// (e.g. some files of a batch failed).
struct ExitStatus {
    int code;
};

/// A warning line on stderr when `database` holds learned weights of `descriptor` (empty: the
/// only kind) that were learned before the database last changed: they are ignored.
void warn_if_weights_stale(const std::string& database, const std::string& descriptor);

/// Adds the command `name`: `summary` (one line) is its line in `esf --help` and the first line
/// of its own --help, which ends with `details` (below its options).
CLI::App* add_command(CLI::App& app, const std::string& name, const std::string& summary,
                      const std::string& details);

/// --threads N, every command's thread count: 0 = all cores; a negative count is refused, and a
/// count above esf::max_threads() (4 x the cores) becomes that, with a warning line on stderr.
CLI::Option* add_threads_option(CLI::App& cmd, int& threads);
/// --seed S with the help text `what`, every command's seed: a negative value is refused (CLI11
/// would otherwise wrap -1 around to 2^64 - 1).
CLI::Option* add_seed_option(CLI::App& cmd, std::uint64_t& seed, const std::string& what);

/// An option `name` whose values are the names of an enum (its EnumNames table): CLI11 checks
/// and lists the choices, the default shown is the name of `value` as it is now, and the value
/// named is stored into `value` (which must outlive `cmd`).
template <NamedEnum Enum>
CLI::Option* add_enum_option(CLI::App& cmd, const std::string& name, Enum& value,
                             const std::string& help) {
    return cmd
        .add_option_function<std::string>(
            name, [&value](const std::string& text) { value = parse_enum<Enum>(text); }, help)
        ->check(CLI::IsMember(enum_names<Enum>()))
        ->default_str(to_string(value));
}
/// --catalog CSV and --no-catalog (exclusive): how a mesh root's models are sized and grouped.
void add_catalog_options(CLI::App& cmd, std::string& catalog, bool& no_catalog);

/// --groups, --exclude-groups, --categories, --fold K/N and --other-folds K/N: which catalog
/// groups of a root a command takes (esf::GroupSelection). Call selection() after parsing.
class GroupOptions {
  public:
    void add_to(CLI::App& cmd);
    esf::GroupSelection selection() const;

  private:
    std::vector<std::string> only_, except_, categories_;
    std::string fold_, other_folds_;
};

/// True when stderr is a terminal (progress bars are drawn only then).
bool stderr_is_terminal();

/// A one-line progress bar on stderr, redrawn at most ~10 times a second; silent when stderr
/// is not a terminal.
class Progress {
  public:
    Progress(std::string label, std::size_t total);
    ~Progress();
    void update(std::size_t done, const std::string& detail = {});
    void finish();

  private:
    std::string label_;
    std::size_t total_;
    bool enabled_;
    double start_;
    double last_draw_ = -1.0;
    bool finished_ = false;
};

}  // namespace esf::cli
