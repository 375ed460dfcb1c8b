// The simulated sensors against their configuration: every statistic is estimated from the
// simulated samples and compared with the value the configuration implies by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "ctxfuse/sim/drive.hpp"

namespace sim = ctxfuse::sim;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double stddev(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m += x;
  m /= static_cast<double>(v.size());
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}
double mean(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m += x;
  return m / static_cast<double>(v.size());
}

const sim::Drive& default_drive() {
  static const sim::Drive d = sim::simulate_drive(sim::DriveConfig{});
  return d;
}

}  // namespace

TEST(SimRoute, RegionSharesMatchTheConfiguration) {
  const auto& d = default_drive();
  const auto s = d.region_shares();
  EXPECT_NEAR(s[0], 0.343, 0.01);
  EXPECT_NEAR(s[1], 0.191, 0.01);
  EXPECT_NEAR(s[2], 0.466, 0.01);
  EXPECT_NEAR(d.duration(), 540.0, 2.0);

  sim::DriveConfig c;
  c.route.region_shares = {0.5, 0.2, 0.3};
  c.route.duration_s = 400.0;
  c.route.indoor_laps = 2;
  const auto d2 = sim::simulate_drive(c);
  const auto s2 = d2.region_shares();
  EXPECT_NEAR(s2[0], 0.5, 0.02);
  EXPECT_NEAR(s2[1], 0.2, 0.02);
  EXPECT_NEAR(s2[2], 0.3, 0.02);
  EXPECT_NEAR(d2.duration(), 400.0, 4.0);
}

TEST(SimRoute, TruthLabelsAgreeWithTheWorldAndStopsAreStatic) {
  const auto& d = default_drive();
  int stops = 0;
  double run = 0.0;
  bool prev_static = false;
  for (const auto& t : d.truth) {
    EXPECT_EQ(t.region, d.world().region_at(t.position));
    if (t.region == sim::Region::indoor) {
      EXPECT_EQ(t.scene, sim::Scene::indoor);
    }
    if (t.region == sim::Region::transition) {
      EXPECT_EQ(t.scene, sim::Scene::obstructed);
    }
    if (t.is_static) {
      EXPECT_EQ(t.speed, 0.0);
      EXPECT_EQ(t.angular_rate.norm(), 0.0);
      EXPECT_NEAR(t.specific_force.z(), sim::kGravity, 1e-12);
      run += 0.01;
    } else if (prev_static) {
      stops += run >= 5.0 ? 1 : 0;
      run = 0.0;
    }
    prev_static = t.is_static;
  }
  stops += run >= 5.0 ? 1 : 0;
  EXPECT_EQ(stops, 6);  // start, traffic light, gate, parking, traffic light, end
  // Both scenes of the outdoor region occur.
  int open = 0, obstructed_outdoor = 0;
  for (const auto& t : d.truth) {
    open += t.scene == sim::Scene::open;
    obstructed_outdoor += t.region == sim::Region::outdoor && t.scene == sim::Scene::obstructed;
  }
  EXPECT_GT(open, 3000);
  EXPECT_GT(obstructed_outdoor, 1500);
}

TEST(SimImu, WhiteNoiseBiasAndScaleMatchTheConfiguration) {
  sim::DriveConfig c;
  c.seed = 11;
  c.imu.gyro_bias_tau_s = 5.0;  // short correlation time: many independent bias values
  c.imu.accel_bias_tau_s = 5.0;
  const auto d = sim::simulate_drive(c);
  const double gyro_white = c.imu.gyro_noise_density * std::sqrt(c.imu.rate_hz);
  const double accel_white = c.imu.accel_noise_density * std::sqrt(c.imu.rate_hz);
  std::vector<double> rg, ra, rg_static, ra_static, bg, ba;
  for (std::size_t k = 0; k < d.imu.size(); ++k) {
    const auto& m = d.imu[k];
    const auto& t = d.truth[k];
    for (int i = 0; i < 3; ++i) {
      const double eg = m.gyro[i] - (1.0 + d.imu_errors.gyro_scale[i]) * t.angular_rate[i] - d.imu_errors.gyro_bias[k][i];
      const double ea = m.accel[i] - (1.0 + d.imu_errors.accel_scale[i]) * t.specific_force[i] - d.imu_errors.accel_bias[k][i];
      rg.push_back(eg);
      ra.push_back(ea);
      if (t.is_static) {
        // At rest the true rate is zero and the specific force is gravity's reaction.
        rg_static.push_back(m.gyro[i] - d.imu_errors.gyro_bias[k][i]);
        ra_static.push_back(m.accel[i] - (i == 2 ? (1.0 + d.imu_errors.accel_scale[2]) * sim::kGravity : 0.0) -
                            d.imu_errors.accel_bias[k][i]);
      }
      bg.push_back(d.imu_errors.gyro_bias[k][i]);
      ba.push_back(d.imu_errors.accel_bias[k][i]);
    }
  }
  EXPECT_NEAR(stddev(rg) / gyro_white, 1.0, 0.02);
  EXPECT_NEAR(stddev(ra) / accel_white, 1.0, 0.02);
  EXPECT_NEAR(stddev(rg_static) / gyro_white, 1.0, 0.05);
  EXPECT_NEAR(stddev(ra_static) / accel_white, 1.0, 0.05);
  EXPECT_NEAR(mean(rg), 0.0, 4.0 * gyro_white / std::sqrt(static_cast<double>(rg.size())));
  // Gauss-Markov bias: stationary std and the correlation exp(-1) at a lag of tau.
  EXPECT_NEAR(stddev(bg) / c.imu.gyro_bias_sigma, 1.0, 0.15);
  EXPECT_NEAR(stddev(ba) / c.imu.accel_bias_sigma, 1.0, 0.15);
  const std::size_t lag = static_cast<std::size_t>(c.imu.gyro_bias_tau_s * c.imu.rate_hz);
  double num = 0.0, den = 0.0;
  for (std::size_t k = 0; k + lag < d.imu.size(); ++k)
    for (int i = 0; i < 3; ++i) {
      num += d.imu_errors.gyro_bias[k][i] * d.imu_errors.gyro_bias[k + lag][i];
      den += d.imu_errors.gyro_bias[k][i] * d.imu_errors.gyro_bias[k][i];
    }
  EXPECT_NEAR(num / den, std::exp(-1.0), 0.12);
}

TEST(SimImu, ErrorFreeConfigurationReproducesTheTruthExactly) {
  sim::DriveConfig c;
  c.route.duration_s = 200.0;
  c.route.indoor_laps = 1;
  c.imu = {100.0, 0, 0, 300, 0, 0, 0, 300, 0};
  const auto d = sim::simulate_drive(c);
  ASSERT_EQ(d.imu.size(), d.truth.size());
  for (std::size_t k = 0; k < d.imu.size(); ++k) {
    EXPECT_EQ(d.imu[k].gyro, d.truth[k].angular_rate);
    EXPECT_EQ(d.imu[k].accel, d.truth[k].specific_force);
  }
}

TEST(SimGnss, FixErrorsFollowUereTimesDopAndNoFixIndoors) {
  std::vector<double> open_norm, transition_err, transition_expected_var;
  std::array<std::vector<double>, 3> sats_by_region;
  for (std::uint64_t seed : {1, 2, 3}) {
    sim::DriveConfig c;
    c.seed = seed;
    c.gnss.rate_hz = 5.0;
    c.gnss.multipath_tau_s = 1.0;
    const auto d = sim::simulate_drive(c);
    for (const auto& e : d.gnss) {
      sats_by_region[static_cast<std::size_t>(e.region)].push_back(e.num_sats);
      if (e.region == sim::Region::indoor) {
        EXPECT_FALSE(e.has_fix) << "t=" << e.t;
        continue;
      }
      if (e.num_sats < 4) {
        EXPECT_FALSE(e.has_fix);
      }
      if (!e.has_fix) continue;
      // Independent PDOP from the listed elevation/azimuth.
      Eigen::Matrix4d n = Eigen::Matrix4d::Zero();
      for (const auto& s : d.satellites_of(e)) {
        const double el = s.elevation_deg * kDeg, az = s.azimuth_deg * kDeg;
        const Eigen::Vector4d row(-std::cos(el) * std::sin(az), -std::cos(el) * std::cos(az), -std::sin(el), 1.0);
        n += row * row.transpose();
      }
      const Eigen::Matrix4d q = n.inverse();
      EXPECT_NEAR(e.pdop, std::sqrt(q(0, 0) + q(1, 1) + q(2, 2)), 1e-6 * e.pdop);
      const double hdop = std::sqrt(q(0, 0) + q(1, 1));
      EXPECT_NEAR((e.position - d.route.state_at(e.t).position - e.error).norm(), 0.0, 1e-9);
      if (e.scene == sim::Scene::open) {
        EXPECT_EQ(e.multipath_bias.norm(), 0.0);
        for (int i = 0; i < 2; ++i) open_norm.push_back(e.error[i] / (c.gnss.uere_m[0] * hdop / std::sqrt(2.0)));
      }
      if (e.region == sim::Region::transition) {
        const double sh = c.gnss.uere_m[2] * hdop / std::sqrt(2.0), mp = c.gnss.multipath_sigma_m[2];
        for (int i = 0; i < 2; ++i) {
          transition_err.push_back(e.error[i] / std::sqrt(sh * sh + mp * mp));
        }
      }
    }
  }
  ASSERT_GT(open_norm.size(), 2000u);
  EXPECT_NEAR(stddev(open_norm), 1.0, 0.06);
  EXPECT_NEAR(mean(open_norm), 0.0, 0.08);
  ASSERT_GT(transition_err.size(), 1000u);
  EXPECT_NEAR(stddev(transition_err), 1.0, 0.2);
  // Satellite counts: outdoor > transition > indoor on average (the regions overlap epoch by
  // epoch, see FeatureDistributionsOverlapAsConfigured).
  const double out = mean(sats_by_region[0]), tr = mean(sats_by_region[1]), in = mean(sats_by_region[2]);
  EXPECT_GT(out, tr + 4.0);
  EXPECT_GT(tr, in + 4.0);
  EXPECT_GE(out, 18.0);
  EXPECT_LE(out, 30.0);
}

// With the overlap mechanisms switched off (approach canyon full height over its whole length,
// closed doorway, no roadside obstructions, no fading) the three regions separate cleanly:
// every satellite indoors is hidden and the deep canyon leaves only near-axis satellites.
TEST(SimGnss, WithoutOverlapMechanismsTheRegionsSeparate) {
  std::array<std::vector<double>, 3> sats_by_region;
  for (std::uint64_t seed : {1, 2}) {
    sim::DriveConfig c;
    c.seed = seed;
    c.route.approach_open_end_height_m = 12.0;
    c.route.garage_door_height_m = 0.0;
    c.gnss.roadside_obstruction_count = 0;
    c.gnss.cn0_fading_sigma_db = {0.0, 0.0, 0.0};
    const auto d = sim::simulate_drive(c);
    for (const auto& e : d.gnss) sats_by_region[static_cast<std::size_t>(e.region)].push_back(e.num_sats);
  }
  const double out = mean(sats_by_region[0]), tr = mean(sats_by_region[1]), in = mean(sats_by_region[2]);
  EXPECT_GT(out, tr + 8.0);
  EXPECT_GE(out, 18.0);
  EXPECT_GE(tr, 4.0);
  EXPECT_LE(tr, 12.0);
  EXPECT_EQ(in, 0.0);
}

// The default drive's features overlap for the configured physical reasons: outdoor epochs
// with fewer satellites than the transition's median occur only in obstructed streets or by
// roadside obstructions; the approach tracks more satellites at its open end than at the
// garage door; indoors, a few weak satellites are tracked only through the doorway and only
// for the first metres, and never give a fix.
TEST(SimGnss, FeatureDistributionsOverlapAsConfigured) {
  int low_outdoor = 0, indoor_with_sats = 0, indoor_sats = 0;
  double max_indoor_depth = 0.0;
  std::vector<double> open_end, closed_end, los_open_cn0, indoor_cn0;
  for (std::uint64_t seed : {1, 2, 3}) {
    sim::DriveConfig c;
    c.seed = seed;
    const auto d = sim::simulate_drive(c);
    const auto& w = d.world();
    const double approach_west = w.transition.vertices[0].x();  // rectangle(-L, ., 0, .)
    ASSERT_LT(approach_west, -10.0);
    std::vector<double> tr;
    for (const auto& e : d.gnss)
      if (e.region == sim::Region::transition) tr.push_back(e.num_sats);
    std::sort(tr.begin(), tr.end());
    ASSERT_FALSE(tr.empty());
    const double tr_median = tr[tr.size() / 2];
    for (const auto& e : d.gnss) {
      const auto st = d.route.state_at(e.t);
      const Eigen::Vector2d p = st.position.head<2>();
      if (e.region == sim::Region::outdoor && e.num_sats < tr_median) {
        ++low_outdoor;
        bool by_roadside = false;
        for (const auto& o : d.roadside_obstructions) by_roadside = by_roadside || (p - o.centre).norm() <= o.radius_m;
        EXPECT_TRUE(e.scene == sim::Scene::obstructed || by_roadside) << "t=" << e.t;
      }
      if (e.region == sim::Region::transition) {
        const double f = (p.x() - approach_west) / -approach_west;  // 0 at the street, 1 at the door
        if (f < 1.0 / 3.0) open_end.push_back(e.num_sats);
        if (f > 2.0 / 3.0) closed_end.push_back(e.num_sats);
      }
      if (e.scene == sim::Scene::open)
        for (const auto& s : d.satellites_of(e))
          if (s.line_of_sight) los_open_cn0.push_back(s.cn0_dbhz);
      if (e.region != sim::Region::indoor) continue;
      EXPECT_FALSE(e.has_fix) << "t=" << e.t;
      if (e.num_sats == 0) continue;
      ++indoor_with_sats;
      max_indoor_depth = std::max(max_indoor_depth, p.x());  // the doorway is the wall x = 0
      for (const auto& s : d.satellites_of(e)) {
        ++indoor_sats;
        indoor_cn0.push_back(s.cn0_dbhz);
        // By hand: the horizontal ray towards the satellite leaves through the doorway
        // (x = 0, |y| <= 5 m) after `run` metres, below the door top plus the diffraction band.
        const double az = s.azimuth_deg * kDeg;
        ASSERT_LT(std::sin(az), 0.0) << "satellite must be to the west";
        const double run = -p.x() / std::sin(az);
        EXPECT_LE(std::abs(p.y() + run * std::cos(az)), 5.0 + 1e-9);
        const double top = std::atan((c.route.garage_door_height_m - c.gnss.antenna_height_m) / run) / kDeg;
        EXPECT_LE(s.elevation_deg, top + c.gnss.diffraction_band_deg + 1e-9);
        if (s.elevation_deg > top + 1e-9) {
          EXPECT_FALSE(s.line_of_sight);
        }
      }
    }
  }
  EXPECT_GT(low_outdoor, 10);
  ASSERT_GT(open_end.size(), 20u);
  ASSERT_GT(closed_end.size(), 20u);
  EXPECT_GT(mean(open_end), mean(closed_end) + 2.0);
  EXPECT_GT(indoor_with_sats, 5);
  // Loss budget: even a zenith-strength signal (cn0_zenith plus 4 sigma of every noise term)
  // drops below the tracking threshold after this many metres under the roof.
  const auto& g = sim::DriveConfig{}.gnss;
  const double budget = g.cn0_zenith_dbhz + 4.0 * (g.cn0_satellite_sigma_db + g.cn0_noise_los_db + g.cn0_fading_sigma_db[2]) -
                        g.doorway_loss_db - g.tracking_threshold_dbhz;
  EXPECT_LT(max_indoor_depth, budget / g.indoor_loss_db_per_m);
  EXPECT_LT(max_indoor_depth, 25.0);
  ASSERT_GT(indoor_sats, 0);
  EXPECT_LT(mean(indoor_cn0), mean(los_open_cn0) - 5.0);
}

TEST(SimGnss, CanyonVisibilityFollowsTheBuildingEdges) {
  const auto& d = default_drive();
  const auto& g = d.config.gnss;
  int checked = 0, nlos = 0;
  for (const auto& e : d.gnss) {
    const auto st = d.route.state_at(e.t);
    const auto* canyon = d.world().canyon_at(st.position.head<2>());
    for (const auto& s : d.satellites_of(e)) {
      EXPECT_GE(s.elevation_deg, g.elevation_mask_deg);
      EXPECT_GE(s.cn0_dbhz, g.tracking_threshold_dbhz);
      const double sat_dir = std::numbers::pi / 2.0 - s.azimuth_deg * kDeg;
      if (e.region == sim::Region::indoor) continue;  // through the doorway: FeatureDistributionsOverlapAsConfigured
      if (!canyon) {
        const sim::RoadsideObstruction* ob = nullptr;
        for (const auto& o : d.roadside_obstructions)
          if (!ob && (st.position.head<2>() - o.centre).norm() <= o.radius_m) ob = &o;
        if (!ob) {
          EXPECT_TRUE(s.line_of_sight);
          continue;
        }
        // One-sided street wall by hand: tan(edge) = tan(edge_perpendicular) * sin(relative azimuth).
        const double rel = std::sin(sat_dir - ob->axis_yaw_rad);
        const double edge = (rel > 0.0) == ob->left_side ? std::atan(std::tan(ob->edge_deg * kDeg) * std::abs(rel)) / kDeg : 0.0;
        EXPECT_EQ(s.line_of_sight, s.elevation_deg >= edge) << s.sat_id << " t=" << e.t;
        EXPECT_GE(s.elevation_deg, edge - g.diffraction_band_deg);
        continue;
      }
      // Edge elevation by hand: relative azimuth between satellite and street axis; the
      // approach's buildings rise linearly from the configured open-end height at its west
      // end (x = -L) to the full height at the door (x = 0).
      double height = canyon->building_height_m;
      if (canyon->area.contains(Eigen::Vector2d(-1.0, 0.0))) {  // the approach
        const double west = canyon->area.vertices[0].x();
        const double f = std::clamp((st.position.x() - west) / -west, 0.0, 1.0);
        height = d.config.route.approach_open_end_height_m + (canyon->building_height_m - d.config.route.approach_open_end_height_m) * f;
      }
      const double edge = std::atan(height * std::abs(std::sin(sat_dir - canyon->axis_yaw_rad)) / canyon->half_width_m) / kDeg;
      EXPECT_EQ(s.line_of_sight, s.elevation_deg >= edge) << s.sat_id << " t=" << e.t;
      EXPECT_GE(s.elevation_deg, edge - g.diffraction_band_deg);
      ++checked;
      nlos += s.line_of_sight ? 0 : 1;
    }
  }
  EXPECT_GT(checked, 500);
  EXPECT_GT(nlos, 100);
}

TEST(SimUwb, NoiseBiasAndNlosRatesMatchTheConfiguration) {
  std::vector<double> los_err, nlos_err, gap_los, gap_nlos;
  std::array<double, 3> clear{}, transient{};
  sim::DriveConfig c;
  c.uwb.dropout_at_zero = 0.0;
  c.uwb.dropout_at_max = 0.0;
  c.uwb.max_range_los_m = 1000.0;
  c.uwb.max_range_nlos_m = 1000.0;
  c.uwb.transient_nlos_mean_duration_s = 0.3;
  c.uwb.transient_nlos_probability = {0.1, 0.2, 0.15};
  for (std::uint64_t seed : {5, 6, 7}) {
    c.seed = seed;
    const auto d = sim::simulate_drive(c);
    for (const auto& r : d.uwb) {
      const double err = r.range_m - r.true_range_m;
      if (!r.nlos) {
        los_err.push_back(err);
        gap_los.push_back(r.rssi_dbm - r.rssi_first_path_dbm);
      } else {
        nlos_err.push_back(err);
        gap_nlos.push_back(r.rssi_dbm - r.rssi_first_path_dbm);
        EXPECT_GE(r.nlos_bias_m, c.uwb.nlos_bias_min_m);
        EXPECT_LE(r.nlos_bias_m, c.uwb.nlos_bias_max_m);
      }
      // On geometrically clear lines NLOS comes only from the transient-obstacle chain.
      if (r.walls_crossed == 0) {
        const auto reg = static_cast<std::size_t>(d.world().region_at(d.route.state_at(r.t).position));
        clear[reg] += 1.0;
        transient[reg] += r.nlos ? 1.0 : 0.0;
      }
    }
  }
  EXPECT_NEAR(stddev(los_err) / c.uwb.range_noise_m, 1.0, 0.03);
  EXPECT_NEAR(mean(los_err), 0.0, 0.005);
  // NLOS: mean error = mean bias (uniform on [min, max]); always biased long on average.
  EXPECT_NEAR(mean(nlos_err), 0.5 * (c.uwb.nlos_bias_min_m + c.uwb.nlos_bias_max_m), 0.15);
  EXPECT_GT(mean(gap_nlos), mean(gap_los) + 4.0);
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_GT(clear[i], 3000.0) << i;
    EXPECT_NEAR(transient[i] / clear[i], c.uwb.transient_nlos_probability[i], 0.25 * c.uwb.transient_nlos_probability[i]) << i;
  }
}

TEST(SimUwb, RangesThroughWallsAreNlosAndRangeIsLimited) {
  const auto& d = default_drive();
  const auto& c = d.config.uwb;
  int through_walls = 0;
  for (const auto& r : d.uwb) {
    EXPECT_EQ(r.walls_crossed > 0, d.world().walls_crossed(d.route.state_at(r.t).position.head<2>(), r.anchor_position.head<2>()) > 0);
    if (r.walls_crossed > 0) {
      EXPECT_TRUE(r.nlos);
      ++through_walls;
    }
    EXPECT_LE(r.true_range_m, r.nlos ? c.max_range_nlos_m : c.max_range_los_m);
  }
  EXPECT_GT(through_walls, 200);
  // Far outdoors there are no ranges at all.
  std::size_t far_ranges = 0;
  for (const auto& r : d.uwb)
    if (d.route.state_at(r.t).position.head<2>().norm() > 150.0) ++far_ranges;
  EXPECT_EQ(far_ranges, 0u);
}

TEST(SimSpeedAndMag, MatchTheConfiguration) {
  const auto& d = default_drive();
  std::vector<double> res;
  for (const auto& s : d.speed) {
    const double v = d.route.state_at(s.t).speed;
    if (v == 0.0) {
      EXPECT_EQ(s.speed_mps, 0.0);
    } else if (v > 1.0) {
      res.push_back(s.speed_mps - (1.0 + d.speed_scale_error) * v);
    }
  }
  EXPECT_NEAR(stddev(res) / d.config.speed.noise_mps, 1.0, 0.08);
  // Far from the building the magnetometer sees the earth field rotated into the body frame.
  const auto& m = d.config.magnetometer;
  const double h = m.field_ut * std::cos(m.inclination_deg * kDeg);
  const Eigen::Vector3d earth(h * std::sin(m.declination_deg * kDeg), h * std::cos(m.declination_deg * kDeg),
                              -m.field_ut * std::sin(m.inclination_deg * kDeg));
  int far = 0;
  double indoor_dist = 0.0, n_indoor = 0.0, outdoor_dist = 0.0, n_outdoor = 0.0;
  for (const auto& s : d.mag) {
    const auto st = d.route.state_at(s.t);
    if (d.world().region_at(st.position) == sim::Region::indoor) {
      indoor_dist += s.disturbance_ut;
      n_indoor += 1.0;
    } else {
      outdoor_dist += s.disturbance_ut;
      n_outdoor += 1.0;
    }
    if (s.disturbance_ut > 1e-3) continue;
    const double cy = std::cos(st.yaw), sy = std::sin(st.yaw);
    const Eigen::Vector3d body(cy * earth.x() + sy * earth.y(), -sy * earth.x() + cy * earth.y(), earth.z());
    EXPECT_LT((s.field_ut - body).norm(), 6.0 * m.noise_ut);
    ++far;
  }
  EXPECT_GT(far, 1000);
  EXPECT_GT(indoor_dist / n_indoor, 3.0 * outdoor_dist / n_outdoor);
  EXPECT_GT(indoor_dist / n_indoor, 2.0);
}
