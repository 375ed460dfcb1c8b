// A one-line progress indicator on stderr, rewritten in place with '\r'. It shows only when
// stderr is a terminal, or once the task has already run for more than two seconds (so that
// quick runs and logs piped to files stay clean).
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ostream>
#include <string>

namespace ctxfuse::cli {

class Progress {
 public:
  Progress(std::ostream& err, std::string label, double total, bool is_tty = ::isatty(STDERR_FILENO) == 1)
      : err_(err), label_(std::move(label)), total_(total > 0 ? total : 1.0), tty_(is_tty), start_(Clock::now()) {}
  ~Progress() { finish(); }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(double done) {
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    if (!tty_ && elapsed < 2.0) return;
    // At most ten redraws per second.
    if (shown_ && std::chrono::duration<double>(now - last_).count() < 0.1) return;
    last_ = now;
    shown_ = true;
    char buf[128];
    std::snprintf(buf, sizeof buf, "\r%s %5.1f %% (%.1f s)", label_.c_str(), 100.0 * done / total_, elapsed);
    err_ << buf << std::flush;
  }
  /// Clears the line (only if something was drawn).
  void finish() {
    if (!shown_) return;
    err_ << '\r' << std::string(label_.size() + 24, ' ') << '\r' << std::flush;
    shown_ = false;
  }
  bool shown() const { return shown_; }

 private:
  using Clock = std::chrono::steady_clock;
  std::ostream& err_;
  std::string label_;
  double total_;
  bool tty_;
  bool shown_ = false;
  Clock::time_point start_, last_;
};

}  // namespace ctxfuse::cli
