#pragma once
// The fuzzy mode (kernel/snap.h) as the worker's config and commands give it and as its records
// write it: one conversion, one JSON form for `csgtile bool`, `csgtile assemble` and the city
// run's assemble jobs.

#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "csgtile/assembly/assembly.h"
#include "csgtile/kernel/snap.h"

namespace csgtile::worker {

/// Snap options from a distance (world units) and an angle in degrees.
inline kernel::SnapOptions snap_options(double distance, double degrees) {
  return {distance, degrees * M_PI / 180.0};
}

/// What the snap moved: directions, axes_snapped, planes, faces_snapped, max_turn_degrees,
/// max_move.
inline nlohmann::ordered_json snap_report_json(const kernel::SnapReport& r) {
  return {{"directions", r.directions},
          {"axes_snapped", r.axes_snapped},
          {"planes", r.planes},
          {"faces_snapped", r.faces_snapped},
          {"max_turn_degrees", r.max_turn * 180.0 / M_PI},
          {"max_move", r.max_move}};
}

/// How an object fused after escalation (AssembledObject::escalation): snap_distance,
/// snap_angle_degrees and the first fuse's error; null when it was not escalated.
inline nlohmann::ordered_json escalation_json(
    const std::optional<assembly::AssembledObject::Escalation>& e) {
  if (!e) return nullptr;
  return {{"snap_distance", e->snap.distance},
          {"snap_angle_degrees", e->snap.angle * 180.0 / M_PI},
          {"reason", e->reason}};
}

}  // namespace csgtile::worker
