// Named simulator scenarios: DriveConfig factories, so that a study or the demo can report the
// same estimators under different, documented sensor pictures.
//
// "default": DriveConfig{} (the library's drive).
// "paper": the sensor picture that the region paper's results section describes (paper A,
// section 3.2): "LC-GNSS cannot position indoors, its error grows as the vehicle approaches
// the entrance, and its signal is lost once the vehicle is fully inside; UWB positions well
// indoors, its error grows as the vehicle moves outwards, it suffers severe NLOS once the
// vehicle leaves the indoor boundary, and it stops when the vehicle is out of the anchors'
// range"; GNSS alone is scored 6.63 m indoors and UWB alone 3.10 m in the transition region
// (table 3), so both deliver poor data on the wrong side of the door. Two changes, each
// physical, none chosen by looking at estimator results:
//  - every UWB anchor is inside the garage (RouteConfig::approach_uwb_anchors = false): the
//    paper's UWB degrades as soon as the vehicle leaves the building, which anchors covering
//    the approach with line of sight would not do;
//  - the garage's outer walls are opaque to UWB (UwbConfig::garage_walls_opaque): from the
//    approach, a garage anchor is reached round the door jamb, with a range too long by the
//    diffracted path's excess, growing as the vehicle moves away from the door.
// GNSS needs no change: the default already loses the fix under the roof (through the 3 m
// doorway at most 1-2 epochs per drive see 4 satellites, at PDOP > 300, which no receiver
// would turn into a fix) and its error grows towards the door (per-zone figures in the
// ordering study). UWB cannot reach the street either: the approach is 138 m long (the
// route solver's length for the 19.1 % transition share), far beyond a DW1000's range.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

#include "ctxfuse/sim/config.hpp"

namespace ctxfuse::sim {

/// The library's default drive (DriveConfig{}).
inline DriveConfig default_scenario() { return DriveConfig{}; }

/// The region paper's described sensor picture (see the top of this file).
inline DriveConfig paper_scenario() {
  DriveConfig c;
  c.route.approach_uwb_anchors = false;
  c.uwb.garage_walls_opaque = true;
  return c;
}

/// Scenario by name: "default" or "paper". Throws std::invalid_argument naming the unknown one.
inline DriveConfig scenario_config(std::string_view name) {
  if (name == "default") return default_scenario();
  if (name == "paper") return paper_scenario();
  throw std::invalid_argument("sim: unknown scenario '" + std::string(name) + "' (known: default, paper)");
}

}  // namespace ctxfuse::sim
