#pragma once
// Option checks beyond CLI11's own. PositiveNumber and NonNegativeNumber (same names in --help)
// with a short message: CLI11's quote the range up to DBL_MAX in full. +∞ passes (a limit that
// means none); NaN is refused by check_finite_options, run on every parsed command line.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

namespace shapematch::app {

inline CLI::Validator number_at_least_zero(bool strict) {
  return CLI::Validator(
      [strict](std::string& value) -> std::string {
        double x = 0.0;
        if (!CLI::detail::lexical_cast(value, x)) return "not a number: " + value;
        if (std::isnan(x)) return "must be a finite number, not " + value;
        if (strict ? x > 0.0 : x >= 0.0) return {};
        return (strict ? "must be positive, not " : "must not be negative, not ") + value;
      },
      strict ? "POSITIVE" : "NONNEGATIVE");
}

inline CLI::Validator positive_number() { return number_at_least_zero(true); }
inline CLI::Validator non_negative_number() { return number_at_least_zero(false); }

// Every floating-point option's values are numbers: CLI11's range checks let NaN through (each
// comparison with it is false), and a NaN weight or tolerance would surface much later as a
// non-finite LP. ±∞ only where it means "none" (time limits).
inline void check_finite_options(const CLI::App& app) {
  for (const CLI::Option* option : app.get_options()) {
    if (option->get_type_name().find("FLOAT") == std::string::npos) continue;
    const bool limit = option->get_name().find("time-limit") != std::string::npos;
    for (const std::string& value : option->results()) {
      const double x = std::strtod(value.c_str(), nullptr);
      if (std::isnan(x) || (std::isinf(x) && !(limit && x > 0.0)))
        throw CLI::ValidationError(option->get_name(), "must be a finite number, not " + value);
    }
  }
  for (const CLI::App* sub : app.get_subcommands()) check_finite_options(*sub);
}

}  // namespace shapematch::app
