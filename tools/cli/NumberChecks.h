#pragma once
// CLI11's number validators with two things of CLI11 2.1 (Debian bookworm's) mended: they pass
// NaN (every comparison with it is false) and their message prints the bounds with
// std::to_string, so CLI::PositiveNumber refuses 0 with "not in range 0.000000 to <309 digits>".
// The check itself stays CLI11's; these add "finite" and say the rule in words.
// An unsigned option needs one of them too: CLI11 2.1 reads "-3" into a size_t as 2^64 - 3.
#include <CLI/CLI.hpp>

#include <cmath>
#include <string>

namespace stereo_fusion::cli {

/// `check` (a CLI11 validator), also refusing non-finite numbers, that says "'<value>' is not
/// <rule>" when it refuses one (CLI11 prefixes the option's name) and shows `description` in the
/// help.
inline CLI::Validator finiteAnd(const CLI::Validator& check, const std::string& rule,
                                const std::string& description) {
  return CLI::Validator(
      [check, rule](std::string& value) {
        double number = 0.0;
        std::string copy = value;
        if (!CLI::detail::lexical_cast(value, number) || !std::isfinite(number) ||
            !check(copy).empty())
          return "'" + value + "' is not " + rule;
        return std::string();
      },
      description);
}

/// Any finite number.
inline CLI::Validator finiteNumber() { return finiteAnd(CLI::Number, "a finite number", "FINITE"); }

/// A finite number > 0.
inline CLI::Validator positiveNumber() {
  return finiteAnd(CLI::PositiveNumber, "a number > 0", "POSITIVE");
}

/// A finite number >= 0.
inline CLI::Validator nonNegativeNumber() {
  return finiteAnd(CLI::NonNegativeNumber, "a number >= 0", "NONNEGATIVE");
}

/// A finite number in (0, hi].
inline CLI::Validator positiveUpTo(double hi) {
  const std::string range = "(0, " + CLI::detail::to_string(hi) + "]";
  return finiteAnd(CLI::PositiveNumber & CLI::Range(0.0, hi), "a number in " + range,
                   "in " + range);
}

/// A finite number in [lo, hi].
inline CLI::Validator numberIn(double lo, double hi) {
  const std::string range =
      "[" + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) + "]";
  return finiteAnd(CLI::Range(lo, hi), "a number in " + range, "in " + range);
}

}  // namespace stereo_fusion::cli
