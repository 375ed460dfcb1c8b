// Reading back the plots of `ctxfuse ... --plot DIR` (tools/cli/plot.hpp): each NAME.png is
// kept beside NAME.gp and NAME.dat, whose series are a "# label" line, then "x y" rows, data
// sets separated by blank lines. The tests compare those rows with the command's JSON.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace ctxfuse::test {

inline bool gnuplot_installed() { return std::system("command -v gnuplot > /dev/null 2>&1") == 0; }

using PlotSeries = std::vector<std::pair<double, double>>;
using PlotData = std::map<std::string, PlotSeries>;  // label -> rows

inline PlotData read_plot_data(const std::filesystem::path& dat) {
  PlotData out;
  std::ifstream in(dat);
  std::string line;
  PlotSeries* current = nullptr;
  while (std::getline(in, line)) {
    if (line.rfind("# ", 0) == 0) {
      current = &out[line.substr(2)];
      continue;
    }
    if (line.empty() || !current) continue;
    std::istringstream ss(line);
    double x = 0.0, y = 0.0;
    ss >> x >> y;
    current->emplace_back(x, y);
  }
  return out;
}

/// Asserts that DIR/NAME.png is a non-empty PNG with its .gp and .dat beside it; the series.
inline PlotData expect_plot(const std::filesystem::path& dir, const std::string& name) {
  namespace fs = std::filesystem;
  const fs::path png = dir / (name + ".png");
  EXPECT_TRUE(fs::exists(png)) << png;
  if (!fs::exists(png)) return {};
  std::ifstream in(png, std::ios::binary);
  std::string head(8, '\0');
  in.read(head.data(), 8);
  EXPECT_EQ(head.substr(1, 3), "PNG") << png;
  EXPECT_GT(fs::file_size(png), 1000u) << png;
  EXPECT_TRUE(fs::exists(dir / (name + ".gp"))) << name;
  EXPECT_TRUE(fs::exists(dir / (name + ".dat"))) << name;
  return read_plot_data(dir / (name + ".dat"));
}

/// RMS of the y column (NaN when empty).
inline double rms_y(const PlotSeries& s) {
  double sum = 0.0;
  for (const auto& p : s) sum += p.second * p.second;
  return s.empty() ? std::nan("") : std::sqrt(sum / static_cast<double>(s.size()));
}

inline double max_y(const PlotSeries& s) {
  double m = std::nan("");
  for (const auto& p : s) m = std::isnan(m) ? p.second : std::max(m, p.second);
  return m;
}

/// The .dat's numbers carry 6 significant digits: a figure recomputed from them agrees to that.
inline double six_digits(double v) { return 1e-5 * std::abs(v) + 1e-9; }

}  // namespace ctxfuse::test

/// Skips the test, saying why, when gnuplot is absent (the command then writes no plot).
#define CTXFUSE_REQUIRE_GNUPLOT()                                                                       \
  do {                                                                                                  \
    if (!::ctxfuse::test::gnuplot_installed())                                                          \
      GTEST_SKIP() << "gnuplot is not installed (apt-get install gnuplot-nox): --plot writes no PNG"; \
  } while (0)
