#pragma once
// The fuzzy mode (kernel/snap.h) as the worker's config and commands give it, and the assembly's
// outcome as its records write it: one conversion, one JSON form for `csgtile bool`, `csgtile
// assemble` and the city run's assemble jobs.

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

/// What the snap moved: directions, axes_snapped, planes, faces_snapped, walls_shared,
/// max_turn_degrees, max_move.
inline nlohmann::ordered_json snap_report_json(const kernel::SnapReport& r) {
  return {{"directions", r.directions},
          {"axes_snapped", r.axes_snapped},
          {"planes", r.planes},
          {"faces_snapped", r.faces_snapped},
          {"walls_shared", r.walls_shared},
          {"max_turn_degrees", r.max_turn * 180.0 / M_PI},
          {"max_move", r.max_move}};
}

/// The assembly's deterministic counts (no timings), as `csgtile assemble` and a city cell's
/// record give them: primitives read and failed; candidate, culled, exactly tested and
/// interacting pairs; objects escalated and timed out; what the snap moved.
inline nlohmann::ordered_json assembly_counts_json(const assembly::AssemblyStats& s) {
  return {{"primitives_read", s.primitives_read},
          {"primitives_failed", s.primitives_failed},
          {"candidate_pairs", s.candidate_pairs},
          {"culled_pairs", s.culled_pairs},
          {"exact_tests", s.exact_tests},
          {"interacting_pairs", s.interacting_pairs},
          {"objects_escalated", s.objects_escalated},
          {"objects_timed_out", s.objects_timed_out},
          {"snap", snap_report_json(s.snap)}};
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
