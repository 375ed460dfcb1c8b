// The scoring protocols of studies/hanyang_protocol.hpp on small references computed by hand: the
// authors' trajectory B span (trajectory A's is in tests/pipelines/nlos_uwb_eval_test.cpp), the
// plain whole-run RMSE, custom spans read from text, the choice of protocol (auto, a reference
// that fits neither span), and the trajectory CSV reader with either time column.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ctxfuse/studies/hanyang_protocol.hpp"
#include <unistd.h>

using ctxfuse::io::HanyangReferencePose;

namespace {

HanyangReferencePose pose(double t, double x, double y, double z) {
  HanyangReferencePose p;
  p.t = t;
  p.position = {x, y, z};
  return p;
}

// Trajectory B's gates: start x < 8.6 and y < -7, end (first later) x > 8.6 and y < -7.
const std::vector<HanyangReferencePose> kRef{
    pose(0, 10, -8, 0),   // y < -7 but x > 8.6: not the start
    pose(1, 8, -8, 0),    // span starts (t = 1)
    pose(2, 5, 0, 0),     //
    pose(3, 6, 2, 0.8),   // |z| >= 0.5: dropped by the protocol, kept by the whole run
    pose(4, 9, -8, 0),    // span ends (t = 4)
    pose(5, 20, 0, 0)};
const std::vector<ctxfuse::studies::TimedPoint2> kEst{
    {0.5, {9, -8}},     // before the span; whole run: ref (9, -8), 0
    {1.0, {8, -7}},     // ref (8, -8): 1 (both)
    {1.5, {6.5, -3}},   // ref (6.5, -4): 1 (both)
    {3.0, {7, -4}},     // span: t = 3 dropped, ref halfway (5,0)-(9,-8) = (7, -4): 0; whole run: ref (6, 2): 1 + 36
    {3.5, {8, -3}},     // span: ref (8, -6): 9; whole run: ref halfway (6,2)-(9,-8) = (7.5, -3): 0.25
    {4.0, {11, -8}},    // ref (9, -8): 4 (both)
    {4.5, {14.5, -1}},  // after the span; whole run: ref (14.5, -4): 9
    {6.0, {0, 0}}};     // after the reference: never scored

}  // namespace

TEST(HanyangSpans, TrajectoryBHandComputed) {
  std::vector<double> errors;
  const auto r = ctxfuse::studies::hanyang_rmse_2d(kEst, kRef, ctxfuse::studies::trajectory_b_span(), &errors);
  EXPECT_EQ(r.scored, 5u);
  EXPECT_DOUBLE_EQ(r.t_begin, 1.0);
  EXPECT_DOUBLE_EQ(r.t_end, 4.0);
  EXPECT_NEAR(r.rmse_2d, std::sqrt(15.0 / 5.0), 1e-12);
  ASSERT_EQ(errors.size(), kEst.size());
  EXPECT_TRUE(std::isnan(errors[0]));
  EXPECT_NEAR(errors[4], 3.0, 1e-12);
  EXPECT_TRUE(std::isnan(errors[6]));
}

TEST(HanyangSpans, WholeRunHandComputed) {
  std::vector<double> errors;
  const auto r = ctxfuse::studies::plain_rmse_2d(kEst, kRef, &errors);
  EXPECT_EQ(r.scored, 7u);
  EXPECT_NEAR(r.rmse_2d, std::sqrt(52.25 / 7.0), 1e-12);
  EXPECT_NEAR(errors[3], std::sqrt(37.0), 1e-12);
  EXPECT_NEAR(errors[4], 0.5, 1e-12);
  EXPECT_TRUE(std::isnan(errors[7]));
  EXPECT_THROW(ctxfuse::studies::plain_rmse_2d(kEst, std::vector<HanyangReferencePose>{pose(0, 0, 0, 0)}), std::invalid_argument);
}

TEST(HanyangSpans, ChoiceOfProtocol) {
  // auto: A's start gate (x > 49.3) is never entered, B fits.
  const auto automatic = ctxfuse::studies::choose_protocol("auto", kRef);
  EXPECT_EQ(automatic.name, "trajectory_b");
  ASSERT_TRUE(automatic.span.has_value());
  EXPECT_TRUE(automatic.warning.empty());
  EXPECT_NEAR(ctxfuse::studies::score_2d(kEst, kRef, automatic).rmse_2d, std::sqrt(3.0), 1e-12);
  // a: does not fit, said why; scored over the whole run.
  const auto a = ctxfuse::studies::choose_protocol("a", kRef);
  EXPECT_EQ(a.name, "whole_run");
  EXPECT_FALSE(a.span.has_value());
  EXPECT_NE(a.warning.find("never enters the start gate (x>49.3,y>-5)"), std::string::npos) << a.warning;
  EXPECT_NEAR(ctxfuse::studies::score_2d(kEst, kRef, a).rmse_2d, std::sqrt(52.25 / 7.0), 1e-12);
  EXPECT_EQ(ctxfuse::studies::choose_protocol("none", kRef).name, "whole_run");
  EXPECT_TRUE(ctxfuse::studies::choose_protocol("none", kRef).warning.empty());
  // A reference that fits neither span: auto says so for both.
  const std::vector<HanyangReferencePose> yard{pose(0, 0, 0, 0), pose(1, 10, 10, 0), pose(2, 20, 0, 0)};
  const auto neither = ctxfuse::studies::choose_protocol("auto", yard);
  EXPECT_EQ(neither.name, "whole_run");
  EXPECT_NE(neither.warning.find("trajectory A: the reference never enters"), std::string::npos) << neither.warning;
  EXPECT_NE(neither.warning.find("trajectory B: the reference never enters"), std::string::npos) << neither.warning;
  // B's start is entered but its end never follows.
  const std::vector<HanyangReferencePose> half{pose(0, 8, -8, 0), pose(1, 5, 0, 0)};
  EXPECT_NE(ctxfuse::studies::choose_protocol("b", half).warning.find("never reaches the end gate (x>8.6,y<-7)"), std::string::npos);
  EXPECT_THROW(ctxfuse::studies::choose_protocol("c", kRef), std::invalid_argument);
}

TEST(HanyangSpans, CustomSpanText) {
  ctxfuse::studies::HanyangSpan s;
  ASSERT_EQ(ctxfuse::studies::parse_hanyang_span("x>49.3,y>-5/x<=12,y>3.4", s), "");
  const auto a = ctxfuse::studies::trajectory_a_span();
  EXPECT_EQ(ctxfuse::studies::describe(s.start), ctxfuse::studies::describe(a.start));
  EXPECT_EQ(ctxfuse::studies::describe(s.end), ctxfuse::studies::describe(a.end));
  // One axis only, and every comparison: x >= 8 starts at t = 1 (x = 8), y <= 0 first after it
  // at t = 2 (y = 0 exactly); the est at 1.0 and 1.5 score 1 each, 2.0 none exists.
  ASSERT_EQ(ctxfuse::studies::parse_hanyang_span(" x <= 8 / y>=-0.5 ", s), "");
  const auto r = ctxfuse::studies::hanyang_rmse_2d(kEst, kRef, s);
  EXPECT_DOUBLE_EQ(r.t_begin, 1.0);
  EXPECT_DOUBLE_EQ(r.t_end, 2.0);
  EXPECT_EQ(r.scored, 2u);
  EXPECT_NEAR(r.rmse_2d, 1.0, 1e-12);
  const auto custom = ctxfuse::studies::choose_protocol("x<=8/y>=-0.5", kRef);
  EXPECT_EQ(custom.name, "custom");
  for (const char* bad : {"x>1", "x>1/y<2/x>3", "z>1/y<2", "x>>1/y<2", "x>1,x<2/y<1", "x>abc/y<1", "x>1,/y<2", "/y<2", "x1/y<2"})
    EXPECT_NE(ctxfuse::studies::parse_hanyang_span(bad, s), "") << bad;
}

TEST(HanyangSpans, TrajectoryCsvEitherTimeColumn) {
  const auto dir = std::filesystem::temp_directory_path() / ("ctxfuse_hanyang_span_csv_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "ours.csv") << "time_ns,x,y,z\n1732085150571773934,1.5,-2.25,1\n1732085150671773934,1.75,-2,1\n";
    std::ofstream(dir / "theirs.csv") << "timestamp,x,y,z\n1000000000,3,4,1\n";
    std::ofstream(dir / "neither.csv") << "t,x,y,z\n1,3,4,1\n";
  }
  const auto ours = ctxfuse::studies::read_hanyang_estimates(dir / "ours.csv");
  ASSERT_EQ(ours.size(), 2u);
  EXPECT_DOUBLE_EQ(ours[0].t, 1732085150.0 + 0.571773934);
  EXPECT_DOUBLE_EQ(ours[1].p.x(), 1.75);
  const auto theirs = ctxfuse::studies::read_hanyang_estimates(dir / "theirs.csv");
  ASSERT_EQ(theirs.size(), 1u);
  EXPECT_DOUBLE_EQ(theirs[0].t, 1.0);
  try {
    ctxfuse::studies::read_hanyang_estimates(dir / "neither.csv");
    ADD_FAILURE() << "no time column accepted";
  } catch (const ctxfuse::io::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("'timestamp' or 'time_ns'"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}
