// The one option parser of every `ctxfuse` sub-command: CLI11 (Debian libcli11-dev; the tool
// only, never the library target). A command declares its options on a CLI::App, with their
// defaults shown in --help (`->capture_default_str()` or app.option_defaults()), and calls
// parse_options; errors are printed as "ctxfuse <command>: <what>" and are usage errors
// (exit status 2), --help prints the generated help to `out` (exit status 0).
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "cli/registry.hpp"

namespace ctxfuse::cli {

/// A CLI::App with the project's conventions: every option's default is shown in --help.
/// (CLI::App can be neither copied nor moved, so the conventions are set in a constructor and
/// make_app returns a prvalue, which C++17 guarantees is not moved.)
struct CtxfuseApp : CLI::App {
  CtxfuseApp(const std::string& description, const std::string& name) : CLI::App(description, name) {
    option_defaults()->always_capture_default();
    get_formatter()->column_width(34);
  }
};

/// A CLI::App for sub-command `name` with the project's conventions: every option's default
/// is shown in --help, and `description` opens the help text.
inline CtxfuseApp make_app(const std::string& name, const std::string& description) {
  return CtxfuseApp(description, "ctxfuse " + name);
}

/// Parses `args` into `app`. Returns nothing when the command should go on, otherwise the
/// exit status to return: 0 after printing --help to `out`, 2 after printing a usage error
/// (unknown option, missing or malformed value, failed check) to `err`.
inline std::optional<int> parse_options(CLI::App& app, Args args, std::ostream& out, std::ostream& err) {
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
