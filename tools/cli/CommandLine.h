#pragma once
// How every command-line tool reads its arguments: CLI11 parses them; --help prints the usage on
// stdout and ends the tool with 0; a refused command line (unknown option, missing or malformed
// value, a value out of range) prints the reason on stderr and ends it with 2, the code scripts
// and tests know (CLI11's own codes are 100 and up).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

namespace stereo_fusion::cli {

constexpr int kExitBadArguments = 2;

/// Parses argv into `app`'s options. nullopt: go on; else the tool ends with this exit code (0
/// after --help, 2 after a refused command line), what to say already printed.
inline std::optional<int> parseOrExitCode(CLI::App& app, int argc, const char* const* argv) {
  try {
    app.parse(argc, argv);
    return std::nullopt;
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : kExitBadArguments;
  }
}

/// Parses `args` (argv[1..], in order) into `app`'s options; false with the reason in `error`.
/// For callers that hold the arguments as strings (the tests, a tool passing some on).
inline bool parseArguments(CLI::App& app, std::vector<std::string> args, std::string* error) {
  std::reverse(args.begin(), args.end());  // CLI11 takes a vector last argument first
  try {
    app.parse(args);
    return true;
  } catch (const CLI::ParseError& e) {
    *error = e.what();
    return false;
  }
}

}  // namespace stereo_fusion::cli
