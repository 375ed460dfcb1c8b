// Entry point of the ctxfuse CLI: dispatches to the registered sub-commands.
#include <algorithm>
#include <exception>
#include <iostream>
#include <string_view>
#include <vector>

#include "cli/registry.hpp"

namespace ctxfuse::cli {

std::vector<Command>& commands() {
  static std::vector<Command> list;
  return list;
}
std::vector<DemoSection>& demo_sections() {
  static std::vector<DemoSection> list;
  return list;
}

}  // namespace ctxfuse::cli

namespace {

void usage(std::ostream& os) {
  os << "usage: ctxfuse <command> [options]\n\ncommands:\n";
  auto cmds = ctxfuse::cli::commands();
  std::sort(cmds.begin(), cmds.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  for (const auto& c : cmds) os << "  " << c.name << std::string(12 - std::min<std::size_t>(11, c.name.size()), ' ') << c.summary << '\n';
  os << "\n`ctxfuse <command> --help` describes a command.\n";
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string_view> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    usage(args.empty() ? std::cerr : std::cout);
    return args.empty() ? 2 : 0;
  }
  for (const auto& c : ctxfuse::cli::commands()) {
    if (c.name != args[0]) continue;
    try {
      return c.run(ctxfuse::cli::Args(args).subspan(1), std::cout, std::cerr);
    } catch (const std::exception& e) {
      // Commands report their own errors; this is the last line of defence so that a bug
      // still ends with a message and a non-zero status rather than an abort.
      std::cerr << "ctxfuse " << args[0] << ": error: " << e.what() << '\n';
      return 1;
    }
  }
  std::cerr << "ctxfuse: unknown command '" << args[0] << "'\n\n";
  usage(std::cerr);
  return 2;
}
