// `ctxfuse features gnss|nmea|uwb-static`: feature tables for the context classifiers.
// Formats are described in docs/formats.md (section `context`).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <ctxfuse/features/gnss_scene.hpp>
#include <ctxfuse/features/nlos.hpp>
#include <ctxfuse/io/nmea.hpp>
#include <ctxfuse/features/scene_label.hpp>
#include <ctxfuse/io/uwb_static.hpp>

#include "cli/registry.hpp"

namespace {

using ctxfuse::cli::Args;
namespace feat = ctxfuse::features;

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Options as --name value pairs; a repeated or unknown option is a usage error.
class Options {
 public:
  Options(Args args, std::vector<std::string_view> known) {
    for (std::size_t i = 0; i < args.size(); ++i) {
      const auto a = args[i];
      if (std::find(known.begin(), known.end(), a) == known.end())
        throw UsageError("unknown option '" + std::string(a) + "'");
      if (i + 1 >= args.size()) throw UsageError("option '" + std::string(a) + "' needs a value");
      if (values_.count(std::string(a))) throw UsageError("option '" + std::string(a) + "' given twice");
      values_[std::string(a)] = std::string(args[++i]);
    }
  }
  std::optional<std::string> get(const std::string& name) const {
    const auto it = values_.find(name);
    if (it == values_.end()) return std::nullopt;
    return it->second;
  }
  std::string required(const std::string& name) const {
    auto v = get(name);
    if (!v) throw UsageError("missing required option " + name);
    return *v;
  }
  double number(const std::string& name, double fallback) const {
    const auto v = get(name);
    if (!v) return fallback;
    double x = 0;
    const auto [p, ec] = std::from_chars(v->data(), v->data() + v->size(), x);
    if (ec != std::errc{} || p != v->data() + v->size() || !std::isfinite(x))
      throw UsageError("option " + name + ": '" + *v + "' is not a finite number");
    return x;
  }

 private:
  std::map<std::string, std::string> values_;
};

std::string fmt(double v) {
  if (!std::isfinite(v)) return "nan";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::unique_ptr<std::ofstream> open_out(const std::string& path) {
  auto f = std::make_unique<std::ofstream>(path);
  if (!*f) throw std::runtime_error("cannot write '" + path + "'");
  return f;
}

void write_feature_header(std::ostream& os, std::string_view first) {
  os << first;
  for (const auto& n : feat::kGnssSceneFeatureNames) os << ',' << n;
  os << '\n';
}

void write_features(std::ostream& os, const feat::GnssSceneFeatures& f) {
  for (double v : f) os << ',' << fmt(v);
  os << '\n';
}

// ---- features gnss ----------------------------------------------------------------------

constexpr std::string_view kGnssHelp =
    "usage: ctxfuse features gnss --sats CSV [--out CSV] [--window S] [--fill V]\n"
    "  CSV header names the columns time_s, sat_id, elevation_deg, azimuth_deg, cn0_dbhz and\n"
    "  optionally pdop (any order, other columns ignored). Consecutive rows with the same\n"
    "  time_s form one epoch; times must increase between epochs. Empty cn0_dbhz = in view,\n"
    "  not tracked; an epoch row with an empty sat_id and no other values marks an epoch with\n"
    "  no satellites. Writes time_s + the eight scene features per epoch (stdout without --out).\n";

struct SatRow {
  double time = 0;
  std::string id;
  double el = 0, az = 0, cn0 = std::nan(""), pdop = std::nan("");
};

int run_gnss(Args args, std::ostream& out, std::ostream& err) {
  const Options opt(args, {"--sats", "--out", "--window", "--fill"});
  const std::string path = opt.required("--sats");
  feat::GnssSceneConfig config;
  config.window_s = opt.number("--window", config.window_s);
  config.fill_value = opt.number("--fill", config.fill_value);
  if (!(config.window_s > 0.0)) throw UsageError("--window must be > 0");

  std::ifstream in(path);
  if (!in) {
    err << "ctxfuse features gnss: cannot open '" << path << "'\n";
    return 1;
  }
  std::string line;
  std::size_t line_no = 1;
  if (!std::getline(in, line)) {
    err << "ctxfuse features gnss: " << path << ":1: empty file (no header)\n";
    return 1;
  }
  const auto header = feat::detail::split_csv_line(line);
  const std::vector<std::string> names(header.begin(), header.end());
  auto col = [&](std::string_view n) -> int {
    const auto it = std::find(names.begin(), names.end(), n);
    return it == names.end() ? -1 : int(it - names.begin());
  };
  const int c_time = col("time_s"), c_id = col("sat_id"), c_el = col("elevation_deg"), c_az = col("azimuth_deg"),
            c_cn0 = col("cn0_dbhz"), c_pdop = col("pdop");
  for (auto [c, n] : {std::pair{c_time, "time_s"}, {c_id, "sat_id"}, {c_el, "elevation_deg"},
                      {c_az, "azimuth_deg"}, {c_cn0, "cn0_dbhz"}})
    if (c < 0) {
      err << "ctxfuse features gnss: " << path << ":1: column '" << n << "' missing from the header\n";
      return 1;
    }

  std::unique_ptr<std::ofstream> file_out;
  if (auto o = opt.get("--out")) file_out = open_out(*o);
  std::ostream& os = file_out ? *file_out : out;
  write_feature_header(os, "time_s");

  feat::GnssSceneExtractor<> extractor(config);
  std::map<std::string, int> ids;
  std::vector<feat::SatelliteObservation> sats;
  double epoch_time = std::nan(""), epoch_pdop = std::nan("");
  std::size_t epoch_line = 0, epochs = 0;
  auto flush = [&]() -> bool {
    if (std::isnan(epoch_time)) return true;
    feat::GnssSceneFeatures f;
    const auto status = extractor.push({epoch_time, sats, epoch_pdop}, f);
    if (status != feat::GnssFeatureStatus::ok) {
      err << "ctxfuse features gnss: " << path << ":" << epoch_line << ": epoch at time_s " << fmt(epoch_time)
          << ": " << feat::describe(status) << '\n';
      return false;
    }
    os << fmt(epoch_time);
    write_features(os, f);
    ++epochs;
    sats.clear();
    epoch_pdop = std::nan("");
    return true;
  };
  auto fail = [&](int c, std::string_view value, std::string_view why) {
    err << "ctxfuse features gnss: " << path << ":" << line_no << ": column '" << names[c] << "': '" << value
        << "' " << why << '\n';
    return 1;
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const auto f = feat::detail::split_csv_line(line);
    if (f.size() != names.size()) {
      err << "ctxfuse features gnss: " << path << ":" << line_no << ": " << f.size() << " fields, header has "
          << names.size() << '\n';
      return 1;
    }
    double t = 0;
    if (!feat::detail::parse_field(f[c_time], t) || !std::isfinite(t)) return fail(c_time, f[c_time], "is not a finite time");
    if (!std::isnan(epoch_time) && t != epoch_time) {
      if (t < epoch_time) return fail(c_time, f[c_time], "is earlier than the previous epoch");
      if (!flush()) return 1;
    }
    if (std::isnan(epoch_time) || t != epoch_time) epoch_line = line_no;
    epoch_time = t;
    if (c_pdop >= 0 && !f[c_pdop].empty()) {
      double p = 0;
      if (!feat::detail::parse_field(f[c_pdop], p) || !(p > 0.0) || !std::isfinite(p))
        return fail(c_pdop, f[c_pdop], "is not a positive number");
      if (!std::isnan(epoch_pdop) && p != epoch_pdop) return fail(c_pdop, f[c_pdop], "differs from the epoch's earlier pdop");
      epoch_pdop = p;
    }
    if (f[c_id].empty()) continue;  // epoch marker without satellites
    feat::SatelliteObservation s;
    s.id = ids.emplace(std::string(f[c_id]), int(ids.size())).first->second;
    if (!feat::detail::parse_field(f[c_el], s.elevation_deg) || !(std::abs(s.elevation_deg) <= 90.0))
      return fail(c_el, f[c_el], "is not an elevation in [-90, 90] deg");
    if (!feat::detail::parse_field(f[c_az], s.azimuth_deg) || !std::isfinite(s.azimuth_deg))
      return fail(c_az, f[c_az], "is not a finite azimuth");
    if (!f[c_cn0].empty() &&
        (!feat::detail::parse_field(f[c_cn0], s.cn0_dbhz) || !(s.cn0_dbhz >= 0.0 && s.cn0_dbhz <= 100.0)))
      return fail(c_cn0, f[c_cn0], "is not a C/N0 in [0, 100] dB-Hz");
    for (const auto& o : sats)
      if (o.id == s.id) return fail(c_id, f[c_id], "appears twice in one epoch");
    if (sats.size() >= 128) return fail(c_id, f[c_id], "exceeds 128 satellites in one epoch");
    sats.push_back(s);
  }
  if (!flush()) return 1;
  err << "features gnss: " << epochs << " epochs from " << path << '\n';
  return 0;
}

// ---- features nmea ----------------------------------------------------------------------

constexpr std::string_view kNmeaHelp =
    "usage: ctxfuse features nmea --nmea FILE --reference GGA_FILE [--out CSV]\n"
    "         [--meta CSV] [--open-max-error M] [--train-fraction F --train-out CSV --test-out CSV]\n"
    "  Parses the receiver's NMEA (GGA/GSA/GSV, checksums verified), computes the eight scene\n"
    "  features per epoch, labels each epoch from its horizontal error against the reference\n"
    "  GGA (0 open: error < M, default 0.6 m; 1 obstructed; 2 no GNSS position) and writes\n"
    "  `label` + features (classifier CSV). --meta writes time_s, error, fix quality per row.\n"
    "  --train-fraction splits the labelled epochs in time order: the first F go to --train-out,\n"
    "  the rest to --test-out. Prints parse statistics and the error distribution.\n";

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * double(v.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const auto hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - double(lo)) * (v[hi] - v[lo]);
}

void print_nmea_stats(std::ostream& out, const std::string& name, const feat::nmea::NmeaLog& log) {
  const auto& s = log.stats;
  out << name << ": " << s.lines << " lines, " << log.epochs.size() << " epochs, " << s.sentences_used
      << " sentences used, " << s.ignored << " ignored types, " << s.checksum_failures << " bad checksums, "
      << s.malformed << " malformed, " << s.satellites_without_geometry << " satellites without elevation/azimuth\n";
  for (const auto& p : s.first_problems) out << "  " << name << ":" << p.line << ": " << p.message << '\n';
}

int run_nmea(Args args, std::ostream& out, std::ostream& err) {
  const Options opt(args, {"--nmea", "--reference", "--out", "--meta", "--open-max-error", "--train-fraction",
                           "--train-out", "--test-out"});
  const std::string nmea_path = opt.required("--nmea"), ref_path = opt.required("--reference");
  feat::SceneLabelThresholds thresholds;
  thresholds.open_max_error_m = opt.number("--open-max-error", 0.6);
  if (!(thresholds.open_max_error_m > 0.0)) throw UsageError("--open-max-error must be > 0");
  const double train_fraction = opt.number("--train-fraction", std::nan(""));
  const bool split = !std::isnan(train_fraction);
  if (split && !(train_fraction > 0.0 && train_fraction < 1.0)) throw UsageError("--train-fraction must be in (0, 1)");
  if (split != (opt.get("--train-out").has_value() && opt.get("--test-out").has_value()))
    throw UsageError("--train-fraction needs both --train-out and --test-out (and vice versa)");

  const auto rx = feat::nmea::read_nmea_file(nmea_path);
  const auto ref = feat::nmea::read_nmea_file(ref_path);
  print_nmea_stats(out, nmea_path, rx);
  print_nmea_stats(out, ref_path, ref);

  // Features over every receiver epoch in order (window statistics need the full history).
  feat::GnssSceneExtractor<> extractor;
  std::vector<feat::GnssSceneFeatures> features(rx.epochs.size());
  std::vector<bool> valid(rx.epochs.size(), false);
  std::vector<feat::SatelliteObservation> storage;
  std::size_t rejected = 0;
  for (std::size_t i = 0; i < rx.epochs.size(); ++i) {
    if (std::isnan(rx.epochs[i].time_s)) continue;
    const auto status = extractor.push(feat::to_gnss_epoch(rx.epochs[i], storage), features[i]);
    valid[i] = status == feat::GnssFeatureStatus::ok;
    if (!valid[i] && rejected++ < 5)
      err << "  epoch at t = " << fmt(rx.epochs[i].time_s) << " s skipped: " << feat::describe(status) << '\n';
  }

  auto labelled = feat::label_scenes(rx.epochs, ref.epochs, thresholds);
  std::erase_if(labelled, [&](const auto& e) { return !valid[e.epoch_index]; });
  if (labelled.empty()) {
    err << "ctxfuse features nmea: no receiver epoch matches a reference epoch in time\n";
    return 1;
  }

  std::array<std::size_t, 3> counts{};
  std::vector<double> errors;
  std::map<int, std::vector<double>> by_quality;
  for (const auto& e : labelled) {
    ++counts[e.label];
    if (std::isfinite(e.horizontal_error_m)) {
      errors.push_back(e.horizontal_error_m);
      by_quality[rx.epochs[e.epoch_index].gga->quality].push_back(e.horizontal_error_m);
    }
  }
  out << "labelled epochs: " << labelled.size() << " (open " << counts[0] << ", obstructed " << counts[1]
      << ", no position " << counts[2] << "; open = horizontal error < " << fmt(thresholds.open_max_error_m)
      << " m)\n";
  out << "horizontal error [m] quantiles 10/50/90/99 %: " << fmt(quantile(errors, 0.1)) << " / "
      << fmt(quantile(errors, 0.5)) << " / " << fmt(quantile(errors, 0.9)) << " / " << fmt(quantile(errors, 0.99))
      << "; max " << fmt(errors.empty() ? std::nan("") : *std::max_element(errors.begin(), errors.end())) << '\n';
  for (const auto& [q, v] : by_quality)
    out << "  GGA quality " << q << ": " << v.size() << " epochs, median error " << fmt(quantile(v, 0.5))
        << " m, >= threshold " << std::count_if(v.begin(), v.end(), [&](double x) { return x >= thresholds.open_max_error_m; })
        << '\n';

  auto write_rows = [&](std::ostream& os, std::size_t begin, std::size_t end) {
    os << "label";
    for (const auto& n : feat::kGnssSceneFeatureNames) os << ',' << n;
    os << '\n';
    for (std::size_t k = begin; k < end; ++k) {
      os << labelled[k].label;
      write_features(os, features[labelled[k].epoch_index]);
    }
  };
  if (auto o = opt.get("--out")) write_rows(*open_out(*o), 0, labelled.size());
  if (auto o = opt.get("--meta")) {
    auto f = open_out(*o);
    *f << "time_s,label,horizontal_error_m,gga_quality\n";
    for (const auto& e : labelled)
      *f << fmt(rx.epochs[e.epoch_index].time_s) << ',' << e.label << ',' << fmt(e.horizontal_error_m) << ','
         << (rx.epochs[e.epoch_index].gga ? rx.epochs[e.epoch_index].gga->quality : 0) << '\n';
  }
  if (split) {
    const auto cut = static_cast<std::size_t>(std::llround(train_fraction * double(labelled.size())));
    write_rows(*open_out(*opt.get("--train-out")), 0, cut);
    write_rows(*open_out(*opt.get("--test-out")), cut, labelled.size());
    auto count_label = [&](std::size_t b, std::size_t e, int l) {
      return std::count_if(labelled.begin() + b, labelled.begin() + e, [&](const auto& x) { return x.label == l; });
    };
    out << "time-blocked split: train = first " << cut << " epochs (t " << fmt(rx.epochs[labelled[0].epoch_index].time_s)
        << " .. " << fmt(rx.epochs[labelled[cut - 1].epoch_index].time_s) << " s; open " << count_label(0, cut, 0)
        << ", obstructed " << count_label(0, cut, 1) << ", no position " << count_label(0, cut, 2)
        << "), test = last " << labelled.size() - cut << " (open " << count_label(cut, labelled.size(), 0)
        << ", obstructed " << count_label(cut, labelled.size(), 1) << ", no position "
        << count_label(cut, labelled.size(), 2) << ")\n";
  }
  return 0;
}

// ---- features uwb-static ----------------------------------------------------------------

constexpr std::string_view kUwbHelp =
    "usage: ctxfuse features uwb-static --data DIR --out CSV [--heights H1,H2,...] [--window N]\n"
    "  Reads DIR/{LOS,NLOS}/height_<h>cm/<d>m.csv and writes one row per range:\n"
    "  label (1 NLOS, 0 LOS), true_distance_m, then with --window 1 (default)\n"
    "  range_residual_m (measured - true), rssi_dbm, rssi_minus_fp_db; with --window N > 1\n"
    "  the causal statistics of the recording's last N ranges: residual_mean_m,\n"
    "  residual_std_m, rssi_mean_dbm, rssi_minus_fp_mean_db. --heights keeps only the listed\n"
    "  heights [cm]. Prints the mean residual of LOS and NLOS ranges per height.\n";

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    double v = 0;
    const auto [p, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || ec != std::errc{} || p != item.data() + item.size())
      throw UsageError("--heights: '" + item + "' is not a number");
    out.push_back(v);
  }
  return out;
}

int run_uwb_static(Args args, std::ostream& out, std::ostream& err) {
  const Options opt(args, {"--data", "--out", "--heights", "--window"});
  const std::string dir = opt.required("--data"), out_path = opt.required("--out");
  const auto heights = opt.get("--heights") ? parse_list(*opt.get("--heights")) : std::vector<double>{};
  const double window_arg = opt.number("--window", 1.0);
  if (!(window_arg >= 1.0 && window_arg <= 64.0) || window_arg != std::floor(window_arg))
    throw UsageError("--window must be an integer in [1, 64]");
  const int window = static_cast<int>(window_arg);
  feat::UwbStaticReadStats stats;
  std::vector<feat::UwbStaticRange> ranges;
  try {
    ranges = feat::read_uwb_static_dataset(dir, heights, stats);
  } catch (const feat::UwbDataError& e) {
    err << "ctxfuse features uwb-static: " << e.what() << '\n';
    return 1;
  }
  if (ranges.empty()) {
    err << "ctxfuse features uwb-static: no ranges found under '" << dir << "' for the requested heights\n";
    return 1;
  }
  auto f = open_out(out_path);
  if (window == 1)
    *f << "label,true_distance_m,range_residual_m,rssi_dbm,rssi_minus_fp_db\n";
  else
    *f << "label,true_distance_m,residual_mean_m,residual_std_m,rssi_mean_dbm,rssi_minus_fp_mean_db\n";
  feat::RangeWindowFeatures<64> stats_window(window);
  std::size_t nlos = 0, current_file = static_cast<std::size_t>(-1);
  struct Sum {
    double residual = 0.0;
    std::size_t n = 0;
  };
  std::map<double, std::array<Sum, 2>> per_height;
  for (const auto& r : ranges) {
    if (r.file_index != current_file) {
      stats_window.reset();
      current_file = r.file_index;
    }
    auto& s = per_height[r.height_cm][r.nlos ? 1 : 0];
    s.residual += r.range_residual_m();
    ++s.n;
    nlos += r.nlos;
    *f << (r.nlos ? 1 : 0) << ',' << fmt(r.true_distance_m);
    if (window == 1) {
      *f << ',' << fmt(r.range_residual_m()) << ',' << fmt(r.rssi_dbm) << ',' << fmt(r.rssi_minus_first_path_db()) << '\n';
    } else {
      feat::RangeWindowFeatures<64>::Output o;
      stats_window.push(r.range_residual_m(), r.rssi_dbm, r.first_path_rssi_dbm, o);  // finite: reader checked
      *f << ',' << fmt(o.residual_mean_m) << ',' << fmt(o.residual_std_m) << ',' << fmt(o.rssi_mean_dbm) << ','
         << fmt(o.rssi_minus_first_path_mean_db) << '\n';
    }
  }
  out << "uwb-static: " << stats.files << " files, " << ranges.size() << " ranges (" << nlos << " NLOS, "
      << ranges.size() - nlos << " LOS), " << stats.skipped_non_finite_power
      << " rows skipped for non-finite RSSI -> " << out_path << '\n';
  out << "height_cm  LOS_ranges  LOS_mean_residual_m  NLOS_ranges  NLOS_mean_residual_m  NLOS_minus_LOS_m\n";
  for (const auto& [h, s] : per_height) {
    const double los = s[0].n ? s[0].residual / double(s[0].n) : std::nan("");
    const double nl = s[1].n ? s[1].residual / double(s[1].n) : std::nan("");
    char line[160];
    std::snprintf(line, sizeof line, "%9.1f  %10zu  %19.4f  %11zu  %20.4f  %16.4f\n", h, s[0].n, los, s[1].n, nl, nl - los);
    out << line;
  }
  return 0;
}

int run_features(Args args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    (args.empty() ? err : out) << "usage: ctxfuse features gnss|nmea|uwb-static [options]\n\n"
                               << kGnssHelp << '\n' << kNmeaHelp << '\n' << kUwbHelp;
    return args.empty() ? 2 : 0;
  }
  const auto sub = args[0];
  const Args rest = args.subspan(1);
  const bool help = !rest.empty() && (rest[0] == "--help" || rest[0] == "-h");
  try {
    if (sub == "gnss") {
      if (help) return out << kGnssHelp, 0;
      return run_gnss(rest, out, err);
    }
    if (sub == "nmea") {
      if (help) return out << kNmeaHelp, 0;
      return run_nmea(rest, out, err);
    }
    if (sub == "uwb-static") {
      if (help) return out << kUwbHelp, 0;
      return run_uwb_static(rest, out, err);
    }
  } catch (const UsageError& e) {
    err << "ctxfuse features " << sub << ": " << e.what() << "\n(see ctxfuse features " << sub << " --help)\n";
    return 2;
  } catch (const std::exception& e) {
    err << "ctxfuse features " << sub << ": error: " << e.what() << '\n';
    return 1;
  }
  err << "ctxfuse features: unknown sub-command '" << sub << "' (gnss, nmea, uwb-static)\n";
  return 2;
}

const ctxfuse::cli::RegisterCommand reg{
    {"features", "feature tables for context classifiers (gnss, nmea, uwb-static)", run_features}};

}  // namespace
