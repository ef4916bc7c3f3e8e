// Small helpers shared by the command-line tools (not part of the library's interface).
#pragma once

#include <CLI/CLI.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>
#include <vector>

#include "acvo/params.hpp"
#include "acvo/dataset/tum.hpp"

namespace acvo::tools {

// ---------------------------------------------------------------------------------------------
// Command lines (CLI11). Every tool has CLI11's --help layout (description, usage line,
// positionals, options with their defaults, then the footer) and one error style: on stderr
// "TOOL: message", the usage line and "Run with --help for more information.", exit status 2.
// ---------------------------------------------------------------------------------------------

// The exit status for bad arguments (CLI11's own codes are 100 and above).
constexpr int kUsageError = 2;

// "TOOL: message", the usage line and the pointer to --help.
inline std::string usageMessage(const CLI::App& app, const std::string& message) {
  return app.get_name() + ": " + message + "\n" +
         CLI::Formatter().make_usage(&app, app.get_name()) +
         "Run with --help for more information.\n";
}

// The tools' settings: `footer` below the options, options named again take the last value (as
// the tools always did), errors in the style above.
inline void setUpCommandLine(CLI::App& app, const std::string& footer) {
  app.footer(footer);
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.get_formatter()->column_width(34);
  app.failure_message(
      [](const CLI::App* a, const CLI::Error& e) { return usageMessage(*a, e.what()); });
}

// Parses the command line. nullopt: go on; else the exit status: 0 after --help (the help on
// stdout), 2 for bad arguments (the message on stderr). Not CLI11_PARSE: it exits with CLI11's
// codes (105 for a bad value, ...), and the tools' scripts and tests know 2.
inline std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : kUsageError;
  }
  return std::nullopt;
}

// A bad argument found after parsing (a malformed --set, a frame range beyond the data): the
// message in the same style on stderr; returns 2.
inline int usageError(const CLI::App& app, const std::string& message) {
  std::cerr << usageMessage(app, message);
  return kUsageError;
}

// A check (a CLI11 transform: it rewrites the text) for a number option of type T: the whole text
// is a number (std::from_chars: no hexadecimal, no octal) within [lo, hi] (`range` says so in
// words: "at least 1", "within (0, 1e6]"). Hand-written rather than CLI::Range: CLI11 2.1 lets NaN
// through Range, reports a word as "not in range", reads "-1" as 2^64 - 1 for a 64-bit unsigned,
// "010" as octal and a value beyond the type as its largest. The value goes on to CLI11's
// conversion in a form it reads back exactly: a decimal integer, or a hexadecimal float (its
// conversion of a decimal float goes through long double and may round twice).
template <typename T>
CLI::Validator numberIn(T lo, T hi, const std::string& range) {
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        T value{};
        const char* const begin = text.data();
        const char* const end = begin + text.size();
        // A minus sign on an unsigned is a value out of range, not a word.
        const bool negative = std::is_unsigned_v<T> && !text.empty() && text[0] == '-';
        const auto [stop, error] = std::from_chars(begin + (negative ? 1 : 0), end, value);
        if (text.empty() || stop != end ||
            (error != std::errc() && error != std::errc::result_out_of_range)) {
          return std::string(std::is_integral_v<T> ? "expects an integer" : "expects a number") +
                 ", got '" + text + "'";
        }
        if constexpr (std::is_integral_v<T>) {
          if (error == std::errc::result_out_of_range && !negative) {  // beyond the type
            return (text[0] == '-' ? "must be at least " + std::to_string(lo)
                                   : "must be at most " + std::to_string(hi)) +
                   ", got " + text;
          }
        }
        if (negative || error != std::errc() || !(value >= lo && value <= hi)) {
          return "must be " + range + ", got " + text;
        }
        if constexpr (std::is_floating_point_v<T>) {
          char hex[64];
          const auto written =
              std::to_chars(hex, hex + sizeof hex, std::abs(value), std::chars_format::hex);
          text = std::string(std::signbit(value) ? "-0x" : "0x") + std::string(hex, written.ptr);
        } else {
          text = std::to_string(value);
        }
        return "";
      },
      "");  // no description: the option's type name says what it takes
}

// Any number of type T: a finite one for a floating-point type.
template <typename T>
CLI::Validator anyNumber() {
  constexpr T lo = std::numeric_limits<T>::lowest(), hi = std::numeric_limits<T>::max();
  if constexpr (std::is_integral_v<T>) {
    return numberIn<T>(lo, hi, "within [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  } else {
    return numberIn<T>(lo, hi, "a finite number");
  }
}

// --offset S|auto (acvo_eval, acvo_compare): seconds added to the estimates' stamps where they
// are looked up in the reference (the TUM tools' --offset), or auto: estimated from the
// frame-to-frame turns (acvo::estimateClockOffset). `offset` is left empty for auto.
inline CLI::Option* addOffsetOption(CLI::App& app, std::optional<double>& offset,
                                    const std::string& description) {
  CLI::Validator seconds = numberIn<double>(-10.0, 10.0, "within [-10, 10] s, or auto");
  return app
      .add_option_function<std::string>(
          "--offset",
          [&offset](const std::string& text) {
            offset = text == "auto" ? std::nullopt : std::optional<double>(std::stod(text));
          },
          description)
      ->type_name("S|auto")
      ->default_str("0")
      ->transform(CLI::Validator(
          [seconds](std::string& text) mutable {
            return text == "auto" ? std::string() : seconds(text);
          },
          ""));
}

// Linear interpolation between order statistics (q in [0, 1]); 0 for an empty list.
inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * double(v.size() - 1);
  const std::size_t lo = std::size_t(std::floor(pos)), hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - double(lo)) * (v[hi] - v[lo]);
}

// Parameters from a YAML file (empty: the defaults), then each "SECTION.KEY=VALUE" of --set on
// top. Throws std::invalid_argument for a malformed --set, std::runtime_error (naming the key)
// for an unknown key or a bad value.
inline Params loadToolParams(const std::string& config, const std::vector<std::string>& sets) {
  Params p = config.empty() ? Params() : loadParams(config);
  for (const auto& s : sets) {
    const auto dot = s.find('.'), eq = s.find('=');
    if (dot == std::string::npos || eq == std::string::npos || eq < dot) {
      throw std::invalid_argument("--set expects SECTION.KEY=VALUE, got '" + s + "'");
    }
    const std::string yaml =
        s.substr(0, dot) + ":\n  " + s.substr(dot + 1, eq - dot - 1) + ": " + s.substr(eq + 1);
    p = parseParams(yaml, p, "--set " + s);
  }
  return p;
}

// The ground-truth pose nearest in time to `stamp` within 0.02 s (as TUM associates), if any.
inline const StampedPose* nearestPose(const Trajectory& gt, double stamp) {
  const StampedPose* best = nullptr;
  for (const auto& p : gt) {
    if (std::abs(p.stamp - stamp) < 0.02 &&
        (!best || std::abs(p.stamp - stamp) < std::abs(best->stamp - stamp))) {
      best = &p;
    }
  }
  return best;
}

// Resident set size of this process in KiB (VmRSS of /proc/self/status); -1 when unreadable.
inline long residentKiB() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmRSS:") {
      long kib = -1;
      status >> kib;
      return kib;
    }
    status.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return -1;
}

// `text` as a JSON string: quoted, with quotes, backslashes and control characters escaped.
inline std::string jsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
      out += buffer;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace acvo::tools
