// `ctxfuse features gnss|nmea|uwb-static|dw1000`: feature tables for the context classifiers.
// Each sub-command lives in its own file (features_<name>.cpp); formats are described in
// docs/formats.md (section `context`).
#include <exception>
#include <ostream>
#include <string_view>

#include "cli/features_common.hpp"
#include "cli/registry.hpp"

namespace {

using ctxfuse::cli::Args;
namespace fc = ctxfuse::cli::features_cli;

constexpr std::string_view kUsage =
    "usage: ctxfuse features gnss|nmea|uwb-static|dw1000 [options]   (`ctxfuse features <name> --help`: options)\n"
    "  gnss        scene features from a per-satellite CSV (elevation, azimuth, C/N0), optional label join\n"
    "  nmea        scene features labelled by a reference receiver, from NMEA logs\n"
    "  uwb-static  NLOS features from static UWB ranging recordings (Hanyang layout)\n"
    "  dw1000      DW1000 diagnostics (register values) as powers in dBm\n";

int run_features(Args args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    (args.empty() ? err : out) << kUsage;
    return args.empty() ? 2 : 0;
  }
  const auto sub = args[0];
  const Args rest = args.subspan(1);
  try {
    if (sub == "gnss") return fc::run_gnss(rest, out, err);
    if (sub == "nmea") return fc::run_nmea(rest, out, err);
    if (sub == "uwb-static") return fc::run_uwb_static(rest, out, err);
    if (sub == "dw1000") return fc::run_dw1000(rest, out, err);
  } catch (const std::exception& e) {  // unreadable input, unwritable output
    err << "ctxfuse features " << sub << ": error: " << e.what() << '\n';
    return 1;
  }
  err << "ctxfuse features: unknown sub-command '" << sub << "' (gnss, nmea, uwb-static, dw1000)\n";
  return 2;
}

const ctxfuse::cli::RegisterCommand reg_features{
    {"features", "feature tables for context classifiers (gnss, nmea, uwb-static, dw1000)", run_features}};

}  // namespace
