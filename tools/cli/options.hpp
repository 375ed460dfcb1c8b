// The one option parser of every `ctxfuse` sub-command: CLI11 (Debian libcli11-dev; the tool
// only, never the library target). A command declares its options on a CLI::App, with their
// defaults shown in --help (`->capture_default_str()` or app.option_defaults()), and calls
// parse_options; errors are printed as "ctxfuse <command>: <what>" and are usage errors
// (exit status 2), --help prints the generated help to `out` (exit status 0).
#pragma once

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cli/registry.hpp"

namespace ctxfuse::cli {

/// A CLI::App for sub-command `name`; `description` opens the help text. (CLI::App can be
/// neither copied nor moved: the result is a prvalue, which C++17 guarantees is not moved, so
/// both `auto app = make_app(...)` and `CLI::App app = make_app(...)` work. The project's
/// conventions, every option's default shown in --help, are applied by parse_options.)
inline CLI::App make_app(const std::string& name, const std::string& description) {
  return CLI::App(description, "ctxfuse " + name);
}

/// For unsigned options (seeds): digits only. CLI11 2.1 would take "-3" and wrap it round.
inline const CLI::Validator kNonNegativeInteger(
    [](std::string& s) {
      return !s.empty() && s.find_first_not_of("0123456789") == std::string::npos ? std::string()
                                                                                   : "'" + s + "' is not a non-negative integer";
    },
    "", "non-negative integer");

/// For real-valued options that must be > 0 (or >= 0): a finite number in range, said in
/// words. CLI11's PositiveNumber names its range as "0.000000 to 1797693...368.000000", the
/// largest double written out in full. `tag` is what --help shows after the type, as CLI11's
/// own validators do (FLOAT:POSITIVE).
inline CLI::Validator real_at_least(double lowest, bool inclusive, std::string words, std::string tag) {
  return CLI::Validator(
      [=](std::string& s) {
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        const bool number = !s.empty() && end == s.c_str() + s.size() && std::isfinite(v);
        return number && (inclusive ? v >= lowest : v > lowest) ? std::string() : "'" + s + "' is not " + words;
      },
      std::move(tag), words);
}
inline const CLI::Validator kPositiveNumber = real_at_least(0.0, false, "a positive number", "POSITIVE");
inline const CLI::Validator kNonNegativeNumber = real_at_least(0.0, true, "a non-negative number", "NONNEGATIVE");

/// Parses `args` into `app`. Returns nothing when the command should go on, otherwise the
/// exit status to return: 0 after printing --help to `out`, 2 after printing a usage error
/// (unknown option, missing or malformed value, failed check) to `err`.
inline std::optional<int> parse_options(CLI::App& app, Args args, std::ostream& out, std::ostream& err) {
  // Every option's default, i.e. its value before parsing, shown in --help; and every long
  // option name, so that an unknown one is named as such (CLI11 would first complain about a
  // missing required option, or list the stray words in reverse).
  std::vector<std::string> known{"--help"};
  auto prepare = [&](CLI::App& a) {
    a.get_formatter()->column_width(34);
    for (CLI::Option* option : a.get_options()) {
      option->capture_default_str();
      for (const auto& name : option->get_lnames()) known.push_back("--" + name);
    }
  };
  prepare(app);
  for (CLI::App* sub : app.get_subcommands({})) prepare(*sub);
  for (std::string_view a : args) {
    if (!a.starts_with("--")) continue;
    const std::string name(a.substr(0, a.find('=')));
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      err << app.get_name() << ": unknown option '" << name << "'\n";
      err << "(`" << app.get_name() << " --help` lists the options)\n";
      return 2;
    }
  }
  // CLI11 takes the arguments in reverse order.
  std::vector<std::string> reversed;
  reversed.reserve(args.size());
  for (auto it = args.rbegin(); it != args.rend(); ++it) reversed.emplace_back(*it);
  try {
    app.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    out << app.help();
    return 0;
  } catch (const CLI::CallForAllHelp&) {
    out << app.help("", CLI::AppFormatMode::All);
    return 0;
  } catch (const CLI::ParseError& e) {
    err << app.get_name() << ": " << e.what() << '\n';
    err << "(`" << app.get_name() << " --help` lists the options)\n";
    return 2;
  }
  return std::nullopt;
}

}  // namespace ctxfuse::cli
