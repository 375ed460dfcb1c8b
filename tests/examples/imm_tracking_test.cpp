// Runs examples/imm_tracking.cpp and reads its per-fix lines: the IMM's mode probabilities
// must move to the turn model within a few seconds of the turn's start, stay there through
// the turn, and move back to constant velocity within a few seconds of its end.
#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <vector>

namespace {

struct Line {
  double t = 0.0;
  int truth = 0;
  double mu[3] = {0, 0, 0};
  int most_probable = -1;
  double error_m = 0.0;
};

struct ExampleRun {
  int exit_code = -1;
  std::vector<Line> lines;
};

ExampleRun run_example(int seed) {
  ExampleRun run;
  const std::string command = std::string(CTXFUSE_EXAMPLE_IMM_TRACKING) + " " + std::to_string(seed);
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return run;
  char buffer[512];
  while (std::fgets(buffer, sizeof buffer, pipe)) {
    if (buffer[0] == '#' || buffer[0] == '\n') continue;
    std::istringstream in(buffer);
    Line l;
    in >> l.t >> l.truth >> l.mu[0] >> l.mu[1] >> l.mu[2] >> l.most_probable >> l.error_m;
    if (!in) {
      ADD_FAILURE() << "unreadable line: " << buffer;
      continue;
    }
    run.lines.push_back(l);
  }
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

constexpr int kTurn = 2;
constexpr double kSettle = 4.0;  // s allowed for the probabilities to follow a change of mode

// Segments of constant truth mode: [first, last] indices.
struct Segment {
  int truth;
  std::size_t first, last;
};
std::vector<Segment> segments(const std::vector<Line>& lines) {
  std::vector<Segment> out;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (out.empty() || out.back().truth != lines[i].truth) out.push_back({lines[i].truth, i, i});
    out.back().last = i;
  }
  return out;
}

class ImmTrackingExample : public ::testing::TestWithParam<int> {};

TEST_P(ImmTrackingExample, ModeProbabilitiesFollowTheTurnAndComeBack) {
  const ExampleRun run = run_example(GetParam());
  ASSERT_EQ(run.exit_code, 0);
  ASSERT_GE(run.lines.size(), 150u);
  const std::vector<Segment> segs = segments(run.lines);
  // The example's drive: straight, turn, straight.
  ASSERT_EQ(segs.size(), 3u);
  ASSERT_EQ(segs[0].truth, 0);
  ASSERT_EQ(segs[1].truth, kTurn);
  ASSERT_EQ(segs[2].truth, 0);

  for (const Line& l : run.lines) EXPECT_NEAR(l.mu[0] + l.mu[1] + l.mu[2], 1.0, 1e-5) << "t = " << l.t;

  for (const Segment& s : segs) {
    const double start = run.lines[s.first].t;
    // Switched within kSettle of the change (the first segment starts already straight).
    if (s.first > 0) {
      double switched_at = -1.0;
      for (std::size_t i = s.first; i <= s.last && switched_at < 0.0; ++i)
        if ((run.lines[i].most_probable == kTurn) == (s.truth == kTurn)) switched_at = run.lines[i].t;
      ASSERT_GE(switched_at, 0.0) << "never switched in the segment from t = " << start;
      EXPECT_LE(switched_at - start, kSettle) << "segment from t = " << start;
    }
    // After settling: the right side holds (nearly) every epoch and most of the probability.
    int epochs = 0, right = 0;
    double mu_turn = 0.0;
    for (std::size_t i = s.first; i <= s.last; ++i) {
      const Line& l = run.lines[i];
      if (s.first > 0 && l.t - start < kSettle) continue;
      ++epochs;
      right += (l.most_probable == kTurn) == (s.truth == kTurn);
      mu_turn += l.mu[kTurn];
    }
    ASSERT_GT(epochs, 10);
    mu_turn /= epochs;
    EXPECT_GE(right, epochs * 9 / 10) << "segment from t = " << start << ": " << right << " of " << epochs;
    if (s.truth == kTurn)
      EXPECT_GT(mu_turn, 0.8) << "mean turn probability in the turn";
    else
      EXPECT_LT(mu_turn, 0.15) << "mean turn probability on the straight from t = " << start;
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, ImmTrackingExample, ::testing::Values(1, 2, 3));

}  // namespace
