#pragma once
/// \file
/// City-scale assembly (paper §4: topological relations between models become relations
/// inside one model). Primitives → solids; a bounding-box sweep finds candidate pairs;
/// OpenVDB masks of the dilated interiors cull the pairs that cannot meet; the exact kernel
/// test (solid_interference) decides the rest; connected components of the contact graph
/// are the objects, each unified by the kernel's n-ary fuse with its CSG tree and face
/// history. Components are fused in parallel (TBB); the output does not depend on the
/// thread count. With a cell, only the primitives near the cell are read and only the
/// objects anchored in the cell are kept (DESIGN.md §1, cells and halos).

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/grid.h"
#include "csgtile/kernel/primitives.h"
#include "csgtile/kernel/snap.h"

namespace csgtile::assembly {

/// One input primitive; `label` names it in the CSG tree and in object ids (unique).
struct AssemblyPrimitive {
  kernel::PrimitiveSpec spec;
  std::string label;
  /// Primitives of different groups are never one object, even where they touch (buildings
  /// of different footprints: their contact is a relation, a party wall, not a fuse).
  std::string group{};
};

/// A cell of a grid (kernel/grid.h) and the grid: primitives meeting the cell's halo are
/// read; an object belongs to the cell holding its anchor, the minimum (x, y) corner of its
/// bounding box. Objects larger than the halo are reported.
struct CellSpec {
  kernel::Grid grid;  ///< size > 0, halo ≥ 0
  kernel::GridCell cell;
};

struct AssemblyOptions {
  double tolerance = kernel::kDefaultTolerance;  ///< contact tolerance, world units
  double voxel_size = 0.5;                       ///< OpenVDB voxel edge, world units
  bool voxel_culling = true;  ///< false: every candidate pair gets the exact test
  bool broad_phase = true;    ///< false: every pair of solids is a candidate
  int threads = 0;            ///< worker threads; 0 = all cores
  std::optional<CellSpec> cell;
  /// Fuzzy mode for fitted primitives: near-coincidences of the primitives snapped before
  /// anything is built (kernel/snap.h); the objects' CSG leaves hold the snapped primitives.
  /// Zero (the default): the primitives as given.
  kernel::SnapOptions snap;
  /// Escalation (issue #20): an object whose fuse fails is fused again from its own
  /// primitives snapped at growing distances (1, 2, 5, 10, 20, 50, 100 mm beyond snap.distance,
  /// the angle growing alike: 0.5° per 5 mm, at least snap.angle, at most 2°) up to this bound
  /// and to a tenth of its thinnest primitive, until it fuses; AssembledObject::escalation
  /// records the snap that was used and why the first fuse failed. Zero (the default): none.
  double escalate_to = 0.0;
  /// Looked at between the assembly's steps and inside its Booleans: once it fires, assemble
  /// returns Cancelled (a worker shutting down).
  kernel::Interrupt interrupt{};
  /// Time limit of one object's fuse (escalation included), seconds; 0: none. An object that
  /// reaches it is kept unfused like one whose fuse fails (`fused` false, `error` names the
  /// limit, `timed_out` set). Objects that reach it depend on the machine's speed.
  double object_time_limit = 0.0;
  /// With voxel_culling, the pairs whose solids' face counts multiply to at least this, or
  /// with a curved solid, are culled by their voxels; other pairs (two boxes: 36) go straight
  /// to the exact test, which costs them less than voxelising their shells (assemble_bench:
  /// a city of boxes assembles faster without culling). Same objects either way. 0: every
  /// pair is culled by its voxels.
  double voxel_min_face_product = 100.0;
  /// A caller's own anchor rule (a city cell's, by its primitives' anchor cells), instead of
  /// `cell`'s: per input primitive, < 0 when it anchors its object in an earlier cell, 0 in
  /// this one, > 0 in a later one. An object is kept when the least mark of its primitives is
  /// 0. Only the pairs of kept objects' primitives are culled and tested (outward from the
  /// primitives marked 0), so a cell neither tests nor fuses its halo's other objects.
  /// Empty: no such rule; else one mark per primitive.
  std::vector<int> anchor;
};

struct AssemblyStats {
  long long primitives = 0;         ///< in the input
  long long primitives_read = 0;    ///< in the cell and its halo (all without a cell)
  long long primitives_failed = 0;  ///< that could not be built (see Assembly::problems)
  long long candidate_pairs = 0;    ///< from the broad phase (all pairs without it)
  long long culled_pairs = 0;       ///< of those, dropped by the OpenVDB masks
  long long exact_tests = 0;        ///< pairs given the exact test (with `anchor`, the
                                    ///< candidates of other cells' objects get neither)
  long long interacting_pairs = 0;  ///< of those, overlapping or touching
  long long components = 0;         ///< objects found (with `anchor`: those reached)
  long long objects = 0;            ///< fused and returned (anchored in the cell, kept)
  long long objects_failed = 0;     ///< whose fuse failed (kept unfused, with the reason)
  long long objects_escalated = 0;  ///< fused only after escalation
  long long objects_timed_out = 0;  ///< whose fuse reached AssemblyOptions::object_time_limit
  long long objects_past_halo = 0;  ///< reaching past the halo (reported, see problems)
  long long active_voxels = 0;      ///< in all masks
  kernel::SnapReport snap;          ///< what the fuzzy mode moved (zero without it)
  double seconds_build = 0, seconds_broad = 0, seconds_voxel = 0, seconds_exact = 0,
         seconds_fuse = 0, seconds_total = 0;
};

/// A contact between two primitives (indices into the input), as the exact test saw it.
struct Contact {
  int a = 0, b = 0;  ///< a < b
  kernel::Interference kind = kernel::Interference::BoundariesMeet;
};

/// A topologically unified object.
struct AssembledObject {
  std::string id;               ///< "obj-" + the label of its first primitive (stable)
  std::vector<int> primitives;  ///< input indices, ascending
  std::string group;            ///< its primitives' group
  /// The fused solid(s) with the CSG tree (one n-ary fuse over the primitives, or the
  /// primitive alone) and face sources. When the fuse failed: the compound of the unfused
  /// primitive solids under the same tree, and `error` says why.
  kernel::CsgModel model;
  bool fused = true;
  /// The model is one solid that a Boolean's result check (kernel::BooleanOptions::
  /// check_result) found valid: exporters need not check it again. False for a lone
  /// primitive and an unfused object, which are not checked here.
  bool checked = false;
  std::string error;
  bool timed_out = false;  ///< the fuse reached AssemblyOptions::object_time_limit
  /// Set when the object fused only after escalation (AssemblyOptions::escalate_to): the snap
  /// its primitives got, and the first fuse's error.
  struct Escalation {
    kernel::SnapOptions snap;
    std::string reason;
  };
  std::optional<Escalation> escalation;
  double volume = 0;
  kernel::BoundingBox box;
  bool reaches_past_halo = false;
};

struct Assembly {
  std::vector<AssembledObject> objects;  ///< ordered by their first primitive
  std::vector<Contact> contacts;         ///< between primitives of published objects, sorted
  std::vector<std::string> problems;     ///< primitives not built, objects past the halo
  AssemblyStats stats;
};

/// Assembles the primitives. Errors: InvalidArgument (bad options: voxel size or cell),
/// Cancelled (options.interrupt fired). Primitives that cannot be built and objects whose
/// fuse fails or runs out of time do not fail the call: they are counted and named in
/// `problems` / `error`.
kernel::Result<Assembly> assemble(const std::vector<AssemblyPrimitive>& primitives,
                                  const AssemblyOptions& options = {});

/// The city model: a compound of the objects' shapes, its CSG tree one n-ary fuse over the
/// objects' trees (objects do not meet, so their union is their compound), face sources
/// carried over. Checked with check_csg.
kernel::Result<kernel::CsgModel> city_model(const std::vector<AssembledObject>& objects);

}  // namespace csgtile::assembly
