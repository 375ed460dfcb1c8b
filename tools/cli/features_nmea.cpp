// `ctxfuse features nmea`: the scene-detection paper's eight GNSS features per epoch of a
// receiver's NMEA log, each epoch labelled from the receiver's horizontal error against a
// reference receiver (ctxfuse/features/scene_label.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include <ctxfuse/features/gnss_scene.hpp>
#include <ctxfuse/io/nmea.hpp>
#include <ctxfuse/features/scene_label.hpp>

#include "cli/features_common.hpp"
#include "cli/options.hpp"

namespace ctxfuse::cli::features_cli {
namespace {

namespace feat = ctxfuse::features;

void write_features(std::ostream& os, const feat::GnssSceneFeatures& f) {
  for (double v : f) os << ',' << fmt(v);
  os << '\n';
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * double(v.size() - 1);
  const auto lo = static_cast<std::size_t>(pos);
  const auto hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - double(lo)) * (v[hi] - v[lo]);
}

void print_nmea_stats(std::ostream& out, const std::string& name, const ctxfuse::io::nmea::NmeaLog& log) {
  const auto& s = log.stats;
  out << name << ": " << s.lines << " lines, " << log.epochs.size() << " epochs, " << s.sentences_used
      << " sentences used, " << s.ignored << " ignored types, " << s.checksum_failures << " bad checksums, "
      << s.malformed << " malformed, " << s.satellites_without_geometry << " satellites without elevation/azimuth\n";
  for (const auto& p : s.first_problems) out << "  " << name << ":" << p.line << ": " << p.message << '\n';
}

}  // namespace

int run_nmea(Args args, std::ostream& out, std::ostream& err) {
  auto app = make_app("features nmea",
                      "Parses the receiver's NMEA (GGA/GSA/GSV, checksums verified), computes the eight scene features per\n"
                      "epoch, labels each epoch from its horizontal error against the reference GGA (0 open: error <\n"
                      "--open-max-error; 1 obstructed; 2 no GNSS position) and writes `label` + features (classifier CSV).\n"
                      "Prints parse statistics and the error distribution.");
  std::string nmea_path, ref_path, out_path, meta_path, train_out, test_out;
  feat::SceneLabelThresholds thresholds;
  thresholds.open_max_error_m = 0.6;
  double train_fraction = 0.0;
  feat::GnssSceneConfig config;
  app.add_option("--nmea", nmea_path, "receiver NMEA log")->required();
  app.add_option("--reference", ref_path, "reference GGA log (same time base)")->required();
  app.add_option("--out", out_path, "labelled feature CSV of every labelled epoch");
  app.add_option("--meta", meta_path, "time_s, label, horizontal error, GGA quality per row");
  app.add_option("--open-max-error", thresholds.open_max_error_m, "open when the horizontal error [m] is below this")
      ->check(ctxfuse::cli::kPositiveNumber);
  app.add_option("--train-fraction", train_fraction, "split in time order: first F of the labelled epochs to --train-out (0 = no split)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--train-out", train_out, "first part of the split");
  app.add_option("--test-out", test_out, "rest of the split");
  add_window_options(app, config);
  if (const auto status = parse_options(app, args, out, err)) return *status;
  const bool split = train_fraction > 0.0;
  if (split && train_fraction >= 1.0) return usage_error(err, "features nmea", "--train-fraction must be in (0, 1)");
  if (split != (!train_out.empty() && !test_out.empty()))
    return usage_error(err, "features nmea", "--train-fraction needs both --train-out and --test-out (and vice versa)");

  const auto rx = ctxfuse::io::nmea::read_nmea_file(nmea_path);
  const auto ref = ctxfuse::io::nmea::read_nmea_file(ref_path);
  print_nmea_stats(out, nmea_path, rx);
  print_nmea_stats(out, ref_path, ref);

  // Features over every receiver epoch in order (window statistics need the full history).
  feat::GnssSceneExtractor<> extractor(config);
  std::vector<feat::GnssSceneFeatures> features(rx.epochs.size());
  std::vector<bool> valid(rx.epochs.size(), false);
  std::vector<feat::SatelliteObservation> storage;
  std::size_t rejected = 0;
  for (std::size_t i = 0; i < rx.epochs.size(); ++i) {
    if (std::isnan(rx.epochs[i].time_s)) continue;
    const auto status = extractor.push(feat::to_gnss_epoch(rx.epochs[i], storage), features[i]);
    valid[i] = status.accepted();
    if (!valid[i] && rejected++ < 5)
      err << "  epoch at t = " << fmt(rx.epochs[i].time_s) << " s skipped: " << ctxfuse::describe(status.problem) << '\n';
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
  if (!out_path.empty()) write_rows(*open_out(out_path), 0, labelled.size());
  if (!meta_path.empty()) {
    auto f = open_out(meta_path);
    *f << "time_s,label,horizontal_error_m,gga_quality\n";
    for (const auto& e : labelled)
      *f << fmt(rx.epochs[e.epoch_index].time_s) << ',' << e.label << ',' << fmt(e.horizontal_error_m) << ','
         << (rx.epochs[e.epoch_index].gga ? rx.epochs[e.epoch_index].gga->quality : 0) << '\n';
  }
  if (split) {
    const auto cut = static_cast<std::size_t>(std::llround(train_fraction * double(labelled.size())));
    write_rows(*open_out(train_out), 0, cut);
    write_rows(*open_out(test_out), cut, labelled.size());
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

}  // namespace ctxfuse::cli::features_cli
