// PNG plots through gnuplot (Debian package gnuplot-nox). The data and the gnuplot script of
// every plot are kept next to the PNG, so a plot can be regenerated or restyled by hand.
// Without gnuplot the Plotter says so once and every plot call returns false; the run goes on.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace ctxfuse::cli {

class Plotter {
 public:
  /// A named series of 2-D points (x, y).
  struct Series {
    std::string label;
    std::vector<Eigen::Vector2d> points;
    bool lines = true;  // false: points only
  };

  Plotter(std::filesystem::path dir, std::ostream& err) : dir_(std::move(dir)), err_(err) {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec) {
      err_ << "ctxfuse: cannot create plot directory " << dir_ << ": " << ec.message() << "; no plots\n";
      available_ = false;
      return;
    }
    available_ = std::system("command -v gnuplot > /dev/null 2>&1") == 0;
    if (!available_)
      err_ << "ctxfuse: gnuplot not found, no plots written (install it: apt-get install gnuplot-nox)\n";
  }

  bool available() const { return available_; }
  const std::filesystem::path& dir() const { return dir_; }
  const std::vector<std::filesystem::path>& written() const { return written_; }
  /// "plots in DIR: a.png b.png" on one line; nothing when no plot was written.
  void print_written(std::ostream& out) const {
    if (written_.empty()) return;
    out << "plots in " << dir_.string() << ":";
    for (const auto& p : written_) out << ' ' << p.filename().string();
    out << '\n';
  }

  /// Plan view (east/north, metres, equal axes) of several trajectories, e.g. truth first.
  bool trajectory(const std::string& name, const std::string& title, const std::vector<Series>& series) {
    return plot(name, title, "east [m]", "north [m]", "set size ratio -1\n", series);
  }

  /// Empirical CDFs of error samples (one curve per series), e.g. horizontal errors.
  bool error_cdf(const std::string& name, const std::string& title, const std::vector<std::pair<std::string, std::vector<double>>>& errors) {
    std::vector<Series> series;
    for (const auto& [label, values] : errors) {
      std::vector<double> v = values;
      std::sort(v.begin(), v.end());
      Series s{label, {}, true};
      for (std::size_t i = 0; i < v.size(); ++i)
        s.points.emplace_back(v[i], static_cast<double>(i + 1) / static_cast<double>(v.size()));
      series.push_back(std::move(s));
    }
    return plot(name, title, "error [m]", "cumulative probability", "set yrange [0:1]\nset key bottom right\n", series);
  }

  /// Any x/y plot (e.g. error against time); `extra` is gnuplot set-up (e.g. "set logscale y\n").
  bool xy(const std::string& name, const std::string& title, const std::string& xlabel, const std::string& ylabel,
          const std::vector<Series>& series, const std::string& extra = "") {
    return plot(name, title, xlabel, ylabel, extra, series);
  }

 private:
  static std::string quote(const std::string& s) {
    std::string q = "\"";
    for (char c : s) {
      if (c == '"' || c == '\\') q += '\\';
      q += c;
    }
    return q + "\"";
  }

  bool plot(const std::string& name, const std::string& title, const std::string& xlabel, const std::string& ylabel,
            const std::string& extra, const std::vector<Series>& all) {
    // An empty series is left out: gnuplot stops on a plot whose data set has no point.
    std::vector<const Series*> series;
    for (const auto& s : all)
      if (!s.points.empty()) series.push_back(&s);
    if (!available_ || series.empty()) return false;
    const auto dat = dir_ / (name + ".dat");
    const auto gp = dir_ / (name + ".gp");
    const auto png = dir_ / (name + ".png");
    {
      std::ofstream d(dat);
      for (const Series* s : series) {
        d << "# " << s->label << '\n';
        for (const auto& p : s->points) d << p.x() << ' ' << p.y() << '\n';
        d << "\n\n";  // gnuplot data-set separator (index)
      }
      std::ofstream g(gp);
      g << "set terminal pngcairo size 1000,750 noenhanced\n"
        << "set output " << quote(png.string()) << '\n'
        << "set title " << quote(title) << '\n'
        << "set xlabel " << quote(xlabel) << "\nset ylabel " << quote(ylabel) << '\n'
        << "set grid\n" << extra << "plot ";
      for (std::size_t i = 0; i < series.size(); ++i) {
        if (i) g << ", \\\n     ";
        g << quote(dat.string()) << " index " << i << " using 1:2 with " << (series[i]->lines ? "lines lw 2" : "points pt 7 ps 0.5")
          << " title " << quote(series[i]->label);
      }
      g << '\n';
      if (!d || !g) {
        err_ << "ctxfuse: cannot write plot files in " << dir_ << '\n';
        return false;
      }
    }
    const std::string cmd = "gnuplot " + quote(gp.string()) + " 2>&1";
    if (std::system(cmd.c_str()) != 0) {
      err_ << "ctxfuse: gnuplot failed on " << gp << '\n';
      return false;
    }
    written_.push_back(png);
    return true;
  }

  std::filesystem::path dir_;
  std::ostream& err_;
  bool available_ = false;
  std::vector<std::filesystem::path> written_;
};

}  // namespace ctxfuse::cli
