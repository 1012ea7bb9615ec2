#pragma once
// Runs the built `esf` binary (ESF_CLI, set by tests/CMakeLists.txt) for the CLI tests: its exit
// code, stdout and stderr.

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace esf::test {

struct CliRun {
    int code = -1;
    std::string out;
    std::string err;
};

inline std::string read_text(const std::filesystem::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// The path or word in single quotes, for a shell command line (the tests' temporary paths
/// hold no quotes).
inline std::string quoted(const std::string& s) { return "'" + s + "'"; }
inline std::string quoted(const char* s) { return quoted(std::string(s)); }
inline std::string quoted(const std::filesystem::path& p) { return quoted(p.string()); }

/// Runs `esf ARGS` through the shell, stdout and stderr captured in files of `dir`.
inline CliRun run_esf(const std::string& args, const std::filesystem::path& dir) {
    const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string command =
        quoted(ESF_CLI) + " " + args + " >" + quoted(out) + " 2>" + quoted(err);
    const int status = std::system(command.c_str());
    CliRun run;
    run.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    run.out = read_text(out);
    run.err = read_text(err);
    return run;
}

}  // namespace esf::test
