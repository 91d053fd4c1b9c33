// Relations between objects: candidate pairs from bounding boxes, then exact classification
// with the kernel's Booleans: a ∪ b gives both the common volume (overlap and containment)
// and the shared area of touching objects.

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <exception>

#include "csgtile/assembly/broad_phase.h"
#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "export/topology_index.h"

namespace csgtile::worker {

const char* relation_kind_name(RelationKind kind) {
  switch (kind) {
    case RelationKind::Touches:
      return "touches";
    case RelationKind::Overlaps:
      return "overlaps";
    case RelationKind::Contains:
      return "contains";
    case RelationKind::Within:
      return "within";
    case RelationKind::Equals:
      return "equals";
    case RelationKind::Unknown:
      return "unknown";
  }
  return "unknown";
}

RelationKind converse(RelationKind kind) {
  switch (kind) {
    case RelationKind::Contains:
      return RelationKind::Within;
    case RelationKind::Within:
      return RelationKind::Contains;
    default:
      return kind;
  }
}

namespace {

// Volumes and areas of Boolean results are exact to rounding (README "Booleans"); this
// relative margin only absorbs that rounding.
constexpr double kRelative = 1e-8;

struct Measured {
  double volume = 0.0, area = 0.0;
  kernel::BoundingBox box;
};

std::string boolean_error(const char* op, const kernel::Error& e) {
  return std::string(op) + ": " + kernel::error_code_name(e.code) + ": " + e.message;
}

// Classifies one candidate pair. Returns false when the pair has no relation.
bool classify(const kernel::Shape& a, const kernel::Shape& b, const Measured& ma,
              const Measured& mb, const kernel::BooleanOptions& options, ObjectRelation& out) {
  // Boxes that meet hold solids that mostly do not (neighbours across a street or a gap): the
  // Booleans' own contact test (the first half of an operation, stopped at the first
  // contact) rules those out before the common and the union of two whole buildings.
  // Disjoint solids share no volume and no area; a pair the test cannot decide goes on.
  if (auto contact = kernel::solid_interference(a, b, options);
      contact.ok() && contact.value() == kernel::Interference::Disjoint) {
    return false;
  }
  // One union decides both: the volume the two share is what their union lacks of the sum of
  // theirs, and the faces in contact disappear from the union, once from each side.
  auto fused = kernel::boolean_operation(a, b, kernel::BooleanOp::Fuse, options);
  if (!fused.ok()) {
    out.kind = RelationKind::Unknown;
    out.reason = boolean_error("fuse", fused.error());
    return true;
  }
  const kernel::MassProperties union_mass = kernel::mass_properties(fused.value());
  const double scale = std::max(ma.volume, mb.volume);
  const double vc =
      std::min(ma.volume + mb.volume - union_mass.volume, std::min(ma.volume, mb.volume));
  if (vc > kRelative * scale) {
    const bool a_inside = std::abs(ma.volume - vc) <= kRelative * scale;
    const bool b_inside = std::abs(mb.volume - vc) <= kRelative * scale;
    out.kind = a_inside && b_inside ? RelationKind::Equals
               : a_inside           ? RelationKind::Within
               : b_inside           ? RelationKind::Contains
                                    : RelationKind::Overlaps;
    out.common_volume = vc;
    return true;
  }
  const double shared = (ma.area + mb.area - union_mass.area) / 2.0;
  if (shared > kRelative * (ma.area + mb.area)) {
    out.kind = RelationKind::Touches;
    out.shared_area = shared;
    return true;
  }
  return false;
}

}  // namespace

std::vector<ObjectRelation> compute_relations(
    const std::vector<kernel::Shape>& solids, double linear_tolerance, int threads,
    const std::function<bool(std::size_t, std::size_t)>& skip) {
  kernel::BooleanOptions options;
  options.tolerance = linear_tolerance;
  // `threads` bounds TBB's arena (0: TBB's default, one per core) for the broad phases and
  // the pairs' classification.
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);

  // The objects that take part in a pair to classify. Only they need their union and their
  // measures: with `skip`, a first broad phase on the solids' own boxes, grown by twice the
  // tolerance (a superset of the measured boxes below, which are grown by once the
  // tolerance), keeps the objects of an unskipped pair — the index of a run made of cells
  // measures only the objects near a cell's border.
  std::vector<std::size_t> involved;
  if (skip) {
    std::vector<kernel::BoundingBox> first(solids.size());
    for (std::size_t i = 0; i < solids.size(); ++i) {
      first[i] = kernel::bounding_box(solids[i]);
      first[i].enlarge(2.0 * linear_tolerance);
    }
    std::vector<kernel::BoxPair> near;
    arena.execute([&] { near = assembly::parallel_overlapping_boxes(first); });
    std::vector<char> takes_part(solids.size(), 0);
    for (const auto& [i, j] : near) {
      if (!skip(i, j)) takes_part[i] = takes_part[j] = 1;
    }
    for (std::size_t i = 0; i < solids.size(); ++i) {
      if (takes_part[i]) involved.push_back(i);
    }
  } else {
    involved.resize(solids.size());
    for (std::size_t i = 0; i < solids.size(); ++i) involved[i] = i;
  }

  // An object made of several solids that overlap (a plain set of primitives) is measured and
  // compared as the union of its solids, which is what the Booleans take it for; where that
  // union fails, the object is kept as given and its pairs end Unknown with the reason.
  // shapes[k], measured[k]: of solids[involved[k]].
  std::vector<kernel::Shape> shapes;
  shapes.reserve(involved.size());
  for (std::size_t i : involved) shapes.push_back(solids[i]);
  for (kernel::Shape& s : shapes) {
    if (kernel::map_child_shapes(s, kernel::ShapeKind::Solid).size() < 2) continue;
    auto united = kernel::boolean_fuse_all({s}, options);
    if (united.ok()) s = united.value();
  }
  std::vector<Measured> measured(shapes.size());
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const kernel::MassProperties mp = kernel::mass_properties(shapes[k]);
    measured[k] = {mp.volume, mp.area, mp.bounds};
    measured[k].box.enlarge(linear_tolerance);
  }

  // Candidate pairs from the broad phase (boxes grown by the tolerance), as indices into
  // `shapes`; sorted, and so in (a, b) order of the solids too (`involved` is increasing).
  std::vector<kernel::BoundingBox> boxes(measured.size());
  for (std::size_t k = 0; k < measured.size(); ++k) boxes[k] = measured[k].box;
  std::vector<kernel::BoxPair> candidates;
  arena.execute([&] { candidates = assembly::parallel_overlapping_boxes(boxes); });
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (const auto& pair : candidates) {
    if (!skip || !skip(involved[pair.first], involved[pair.second])) pairs.push_back(pair);
  }

  // Pairs are independent (shapes are immutable and shared safely between threads): each
  // result lands in its pair's slot, so the output does not depend on the number of threads
  // or on scheduling.
  std::vector<ObjectRelation> slots(pairs.size());
  std::vector<char> related(pairs.size(), 0);
  const auto classify_pair = [&](std::size_t k) {
    const auto [i, j] = pairs[k];
    ObjectRelation& r = slots[k];
    r.a = involved[i];
    r.b = involved[j];
    try {
      related[k] = classify(shapes[i], shapes[j], measured[i], measured[j], options, r) ? 1 : 0;
    } catch (const std::exception& e) {
      // The kernel does not throw across its API; an allocation failure still might.
      r.kind = RelationKind::Unknown;
      r.reason = std::string("exception: ") + e.what();
      related[k] = 1;
    }
  };
  arena.execute([&] { tbb::parallel_for(std::size_t{0}, pairs.size(), classify_pair); });

  std::vector<ObjectRelation> out;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (related[k]) out.push_back(std::move(slots[k]));
  }
  return out;
}

}  // namespace csgtile::worker
