// Scene labels from the receiver's own position error against a reference (scene paper:
// labels come from the error, not from a map): 0 open, 1 obstructed, 2 no GNSS position
// ("indoor"). Thresholds are parameters because they depend on the receiver grade: the paper's
// single-point receiver is open below a few metres, an RTK receiver below decimetres.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <vector>

#include <ctxfuse/features/gnss_scene.hpp>
#include <ctxfuse/io/nmea.hpp>

namespace ctxfuse::features {

enum SceneLabel : int { scene_open = 0, scene_obstructed = 1, scene_no_position = 2 };

struct SceneLabelThresholds {
  /// Horizontal error below this is "open"; at or above, "obstructed".
  double open_max_error_m = 3.0;
  /// A receiver epoch matches a reference epoch when their times differ by at most this.
  double max_time_offset_s = 0.05;
  /// GGA fix quality 6 (dead reckoning) has no GNSS position: label it "no position".
  bool dead_reckoning_is_no_position = true;
};

struct LabelledSceneEpoch {
  std::size_t epoch_index = 0;  // into the receiver log
  int label = scene_no_position;
  double horizontal_error_m = std::numeric_limits<double>::quiet_NaN();  // NaN without position
};

/// Labels every receiver epoch that has a GGA and a reference epoch within max_time_offset_s;
/// other epochs are left out (no truth). Both logs must be in increasing time order.
inline std::vector<LabelledSceneEpoch> label_scenes(std::span<const io::nmea::NmeaEpoch> receiver,
                                                    std::span<const io::nmea::NmeaEpoch> reference,
                                                    const SceneLabelThresholds& thresholds) {
  std::vector<LabelledSceneEpoch> out;
  std::size_t j = 0;
  for (std::size_t i = 0; i < receiver.size(); ++i) {
    const auto& rx = receiver[i];
    // Without a GGA (e.g. its sentence failed the checksum) the receiver's fix is unknown:
    // no label rather than a guess.
    if (std::isnan(rx.time_s) || !rx.gga) continue;
    while (j < reference.size() &&
           (!reference[j].gga || !reference[j].gga->has_position() ||
            reference[j].time_s < rx.time_s - thresholds.max_time_offset_s))
      ++j;
    if (j >= reference.size()) break;
    if (std::abs(reference[j].time_s - rx.time_s) > thresholds.max_time_offset_s) continue;
    LabelledSceneEpoch e;
    e.epoch_index = i;
    const bool has_position = rx.gga->has_position() &&
                              !(thresholds.dead_reckoning_is_no_position && rx.gga->quality == 6);
    if (has_position) {
      const auto& ref = *reference[j].gga;
      e.horizontal_error_m =
          io::nmea::horizontal_distance_m(rx.gga->latitude_deg, rx.gga->longitude_deg, ref.latitude_deg, ref.longitude_deg);
      e.label = e.horizontal_error_m < thresholds.open_max_error_m ? scene_open : scene_obstructed;
    }
    out.push_back(e);
  }
  return out;
}

/// The satellites of an NMEA epoch as feature-extractor input (ids = io::nmea::satellite_key),
/// written into `storage` (reused between epochs, so a long log does not allocate per epoch).
inline GnssEpoch to_gnss_epoch(const io::nmea::NmeaEpoch& epoch, std::vector<SatelliteObservation>& storage) {
  storage.clear();
  for (const auto& s : epoch.satellites)
    storage.push_back({io::nmea::satellite_key(s.system, s.prn), s.elevation_deg, s.azimuth_deg, s.snr_dbhz});
  return GnssEpoch{epoch.time_s, storage, epoch.pdop};
}

}  // namespace ctxfuse::features
