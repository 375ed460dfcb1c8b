// `ctxfuse features dw1000`: DW1000 receive diagnostics (register values) turned into powers in
// dBm with the user manual's formulas (ctxfuse/features/dw1000.hpp), from a CSV in the
// documented column layout or from the Hanyang static ranging folders.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include <ctxfuse/features/dw1000.hpp>
#include <ctxfuse/io/text.hpp>
#include <ctxfuse/io/uwb_static.hpp>  // detail::number_in_name

#include "cli/features_common.hpp"
#include "cli/options.hpp"

namespace ctxfuse::cli::features_cli {
namespace {

namespace feat = ctxfuse::features;
namespace fs = std::filesystem;

struct Frame {
  int label = -1;  // -1: none
  double height_cm = std::nan("");
  feat::Dw1000Diagnostics d;
};

struct Counts {
  std::size_t files = 0, rows = 0, skipped_unparsable = 0, rejected = 0;
};

/// Frames of one CSV. `names` maps each Dw1000Diagnostics field to its header name. Rows whose
/// first field is not a number end the data (the Hanyang files close with a summary block).
/// A row with an unparsable used field is an error unless `skip_bad_rows` (then counted).
std::vector<Frame> read_frames(const fs::path& path, const std::map<std::string, std::string>& names, bool skip_bad_rows,
                               Counts& counts) {
  io::TextFile file(path);
  const io::Header header = io::read_header(file, io::Separator::comma);
  const auto col = [&](const std::string& key, bool required) {
    if (required) return static_cast<int>(io::require_column(file, header, names.at(key)));
    const auto c = header.find(names.at(key));
    return c ? static_cast<int>(*c) : -1;
  };
  const int c_range = col("range", true), c_f1 = col("fp1", true), c_f2 = col("fp2", true), c_f3 = col("fp3", true),
            c_cir = col("cir", true), c_pacc = col("rxpacc", true), c_noise = col("noise", true), c_label = col("label", false),
            c_prf = col("prf", false);
  std::vector<Frame> out;
  io::Fields f(file.name(), &header);
  ++counts.files;
  while (io::next_fields(file, f, io::Separator::comma)) {
    double first = 0;
    if (skip_bad_rows && io::parse_real(f[0], first, io::kAnyReal) != io::NumberError::none) break;
    if (f.size() != header.size() && skip_bad_rows) {
      ++counts.skipped_unparsable;
      continue;
    }
    f.expect_count(header.size());
    Frame fr;
    bool ok = true;
    // Finite values only; a bad one throws, or with `skip_bad_rows` drops the row.
    const auto get = [&](int c, double& v) {
      if (c < 0 || !ok) return;
      const auto i = static_cast<std::size_t>(c);
      if (!skip_bad_rows) v = f.real(i, io::kAnyFinite);
      else ok = io::parse_real(f[i], v, io::kAnyFinite) == io::NumberError::none;
    };
    double label = -1;
    get(c_range, fr.d.range_m);
    get(c_f1, fr.d.fp_amp1);
    get(c_f2, fr.d.fp_amp2);
    get(c_f3, fr.d.fp_amp3);
    get(c_cir, fr.d.cir_power);
    get(c_pacc, fr.d.rxpacc);
    get(c_noise, fr.d.std_noise);
    get(c_prf, fr.d.prf_mhz);
    get(c_label, label);
    if (!ok) {
      ++counts.skipped_unparsable;
      continue;
    }
    fr.label = c_label >= 0 ? f.whole<int>(static_cast<std::size_t>(c_label), -1'000'000'000, 1'000'000'000) : -1;
    out.push_back(fr);
  }
  return out;
}

}  // namespace

int run_dw1000(Args args, std::ostream& out, std::ostream& err) {
  auto app = make_app("features dw1000",
                      "Turns DW1000 diagnostics into features that carry over between radio settings (DW1000 User Manual\n"
                      "4.7): rx_power_dbm = 10 log10(C 2^17 / N^2) - A, fp_power_dbm = 10 log10((F1^2+F2^2+F3^2) / N^2) - A,\n"
                      "rx_minus_fp_db, noise_dbm = 10 log10(STD_NOISE^2 / N^2) - A, range_m; N = RXPACC, A = 121.74 (PRF\n"
                      "64 MHz) or 113.77 (16 MHz). --data: CSV with columns range_m, fp_amp1, fp_amp2, fp_amp3, cir_power,\n"
                      "rxpacc, std_noise, optional label and prf_mhz (default 64), others ignored. --static: the Hanyang\n"
                      "folders DIR/{LOS,NLOS}/height_<h>cm/<d>m.csv (label 1 = NLOS; rows that do not parse are skipped\n"
                      "and counted). Writes label (when known) and the five features per frame.");
  std::string data, dir, out_path;
  std::vector<double> heights;
  bool height_column = false;
  auto* data_opt = app.add_option("--data", data, "CSV of register values");
  app.add_option("--static", dir, "Hanyang static ranging folder (holding LOS/ and NLOS/)")->excludes(data_opt);
  app.add_option("--out", out_path, "feature CSV")->required();
  app.add_option("--heights", heights, "with --static: keep only these heights [cm] (comma-separated; default: all)")->delimiter(',');
  app.add_flag("--height-column", height_column, "with --static: append a height_cm column (a group column for classify)");
  if (const auto status = parse_options(app, args, out, err)) return *status;
  if (data.empty() == dir.empty()) return usage_error(err, "features dw1000", "give --data CSV or --static DIR");
  try {
    Counts counts;
    std::vector<Frame> frames;
    if (!data.empty()) {
      frames = read_frames(data, {{"range", "range_m"}, {"fp1", "fp_amp1"}, {"fp2", "fp_amp2"}, {"fp3", "fp_amp3"},
                                  {"cir", "cir_power"}, {"rxpacc", "rxpacc"}, {"noise", "std_noise"}, {"label", "label"},
                                  {"prf", "prf_mhz"}},
                           false, counts);
    } else {
      const std::map<std::string, std::string> hanyang{{"range", "Distance"},         {"fp1", "FirstPathAmp1"},
                                                       {"fp2", "FirstPathAmp2"},      {"fp3", "FirstPathAmp3"},
                                                       {"cir", "Max Growth CIR"},     {"rxpacc", "Rx Preamble Count"},
                                                       {"noise", "Standard Noise"},   {"label", "-"},
                                                       {"prf", "-"}};
      for (const auto& [cls, nlos] : {std::pair{"LOS", 0}, {"NLOS", 1}}) {
        std::vector<std::pair<double, fs::path>> folders;
        if (!fs::is_directory(fs::path(dir) / cls)) throw InputError("'" + (fs::path(dir) / cls).string() + "' is not a folder");
        for (const auto& e : fs::directory_iterator(fs::path(dir) / cls)) {
          const double h = ctxfuse::io::detail::number_in_name(e.path().filename().string(), "height_", "cm");
          if (std::isnan(h) || (!heights.empty() && std::find(heights.begin(), heights.end(), h) == heights.end())) continue;
          folders.emplace_back(h, e.path());
        }
        std::sort(folders.begin(), folders.end());
        for (const auto& [h, folder] : folders) {
          std::vector<fs::path> files;
          for (const auto& e : fs::directory_iterator(folder))
            if (e.path().extension() == ".csv") files.push_back(e.path());
          std::sort(files.begin(), files.end());
          for (const auto& file : files)
            for (auto fr : read_frames(file, hanyang, true, counts)) {
              fr.label = nlos;
              fr.height_cm = h;
              frames.push_back(fr);
            }
        }
      }
    }
    const bool labelled = std::any_of(frames.begin(), frames.end(), [](const Frame& f) { return f.label >= 0; });
    auto f = open_out(out_path);
    *f << (labelled ? "label," : "");
    for (std::size_t k = 0; k < feat::kDw1000FeatureNames.size(); ++k) *f << (k ? "," : "") << feat::kDw1000FeatureNames[k];
    *f << (height_column && !dir.empty() ? ",height_cm\n" : "\n");
    for (const auto& fr : frames) {
      feat::Dw1000Features x;
      if (const ctxfuse::Status s = feat::dw1000_features(fr.d, x); !s) {
        if (counts.rejected++ < 5) err << "  frame skipped: " << ctxfuse::describe(s.problem) << '\n';
        continue;
      }
      ++counts.rows;
      if (labelled) *f << fr.label << ',';
      const auto v = x.values();
      for (std::size_t k = 0; k < v.size(); ++k) *f << (k ? "," : "") << fmt(v[k]);
      if (height_column && !dir.empty()) *f << ',' << fmt(fr.height_cm);
      *f << '\n';
    }
    out << "dw1000: " << counts.files << " files, " << counts.rows << " frames written, " << counts.skipped_unparsable
        << " rows skipped (unparsable), " << counts.rejected << " frames rejected (no positive power, bad PRF or RXPACC) -> "
        << out_path << '\n';
    return 0;
  } catch (const std::exception& e) {
    err << "ctxfuse features dw1000: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace ctxfuse::cli::features_cli
