// The simulated site: a parking garage (indoor), a covered approach between tall buildings
// (indoor-outdoor transition) and streets outside (outdoor), in a local ENU frame.
//
// Frames used throughout ctxfuse::sim:
//  - navigation frame: local ENU, x east, y north, z up, metres, origin at the garage
//    entrance (centre of the doorway, ground level);
//  - body frame: FLU, x forward, y left, z up, fixed to the vehicle;
//  - yaw (heading) about z, measured from x (east) counter-clockwise, in radians; roll and
//    pitch are zero on this flat site;
//  - satellite azimuth, as receivers report it: degrees clockwise from north.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "ctxfuse/sim/records.hpp"

namespace ctxfuse::sim {

struct Polygon {
  std::vector<Eigen::Vector2d> vertices;  // ENU x/y, metres, either winding

  /// Even-odd rule; points exactly on an edge may fall on either side.
  bool contains(const Eigen::Vector2d& p) const {
    bool inside = false;
    const std::size_t n = vertices.size();
    for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
      const auto& a = vertices[i];
      const auto& b = vertices[j];
      if ((a.y() > p.y()) != (b.y() > p.y())) {
        const double x_cross = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
        if (p.x() < x_cross) inside = !inside;
      }
    }
    return inside;
  }
  static Polygon rectangle(double x0, double y0, double x1, double y1) {
    return Polygon{{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}};
  }
};

/// A wall as seen by UWB: a vertical obstacle along the segment a-b (ENU, metres).
struct Wall {
  Eigen::Vector2d a;
  Eigen::Vector2d b;
};

/// True when the open segments p-q and a-b cross (touching at an end point does not count).
inline bool segments_cross(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& a,
                           const Eigen::Vector2d& b) {
  auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); };
  const Eigen::Vector2d r = q - p;
  const Eigen::Vector2d s = b - a;
  const double denom = cross(r, s);
  if (std::abs(denom) < 1e-12) return false;  // parallel: a ray grazing along a wall is not blocked
  const double t = cross(a - p, s) / denom;
  const double u = cross(a - p, r) / denom;
  return t > 0.0 && t < 1.0 && u > 0.0 && u < 1.0;
}

/// A street lined with buildings of equal height on both sides (the classic urban-canyon
/// model): a satellite at relative azimuth d from the street axis is blocked below the
/// elevation atan(height * |sin d| / half_width).
struct StreetCanyon {
  Polygon area;                 // where the canyon applies
  double axis_yaw_rad = 0.0;    // street direction, ENU yaw convention (CCW from east)
  double building_height_m = 0.0;
  double half_width_m = 10.0;   // street centre line to building face
  double extra_attenuation_db = 0.0;  // canopies, trees, glass: applies to every satellite
  /// Optional gradual closing: the buildings are open_end_height_m tall at open_end and rise
  /// linearly to building_height_m at closed_end (by projection on that segment; clamped
  /// beyond its ends). open_end_height_m < 0: the same height everywhere.
  Eigen::Vector2d open_end = Eigen::Vector2d::Zero();
  Eigen::Vector2d closed_end = Eigen::Vector2d::Zero();
  double open_end_height_m = -1.0;

  double height_at(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d axis = closed_end - open_end;
    if (open_end_height_m < 0.0 || axis.squaredNorm() <= 0.0) return building_height_m;
    const double f = std::clamp((p - open_end).dot(axis) / axis.squaredNorm(), 0.0, 1.0);
    return open_end_height_m + (building_height_m - open_end_height_m) * f;
  }
  /// Elevation (degrees) below which the buildings hide a satellite at this azimuth
  /// (degrees clockwise from north), for buildings of the given height.
  double mask_elevation_deg(double azimuth_deg, double height_m) const {
    const double sat_yaw = std::numbers::pi / 2.0 - azimuth_deg * std::numbers::pi / 180.0;  // to ENU yaw convention
    const double s = std::abs(std::sin(sat_yaw - axis_yaw_rad));
    return std::atan2(height_m * s, half_width_m) * 180.0 / std::numbers::pi;
  }
  double mask_elevation_deg(double azimuth_deg) const { return mask_elevation_deg(azimuth_deg, building_height_m); }
  double mask_elevation_deg(double azimuth_deg, const Eigen::Vector2d& p) const {
    return mask_elevation_deg(azimuth_deg, height_at(p));
  }
};

/// An opening in a roofed area's wall (the garage doorway) through which satellites low
/// enough in its direction remain visible from inside.
struct Doorway {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  double height_m = 0.0;  // clear height above ground
};

struct UwbAnchor {
  int id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // ENU, metres
};

struct World {
  Polygon indoor;      // garage footprint; its roof hides the whole sky
  Polygon transition;  // covered approach between the buildings
  std::vector<StreetCanyon> canyons;  // obstructed streets, including the transition approach
  std::vector<Wall> walls;            // UWB obstacles: garage walls, pillars, approach walls
  std::vector<UwbAnchor> anchors;
  Doorway garage_door;                // in the indoor polygon's wall

  Region region_at(const Eigen::Vector2d& p) const {
    if (indoor.contains(p)) return Region::indoor;
    if (transition.contains(p)) return Region::transition;
    return Region::outdoor;
  }
  Region region_at(const Eigen::Vector3d& p) const { return region_at(Eigen::Vector2d(p.head<2>())); }

  /// The canyon in force at p, or nullptr in the open.
  const StreetCanyon* canyon_at(const Eigen::Vector2d& p) const {
    for (const auto& c : canyons)
      if (c.area.contains(p)) return &c;
    return nullptr;
  }

  /// Scene as in paper B: indoor under the roof; obstructed in any canyon or the transition
  /// approach; open elsewhere.
  Scene scene_at(const Eigen::Vector2d& p) const {
    switch (region_at(p)) {
      case Region::indoor: return Scene::indoor;
      case Region::transition: return Scene::obstructed;
      case Region::outdoor: break;
    }
    return canyon_at(p) ? Scene::obstructed : Scene::open;
  }

  /// Number of walls the straight line a-b crosses in plan view.
  int walls_crossed(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    int n = 0;
    for (const auto& w : walls) n += segments_cross(a, b, w.a, w.b) ? 1 : 0;
    return n;
  }
};

}  // namespace ctxfuse::sim
