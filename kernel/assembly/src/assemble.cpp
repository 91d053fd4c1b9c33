// City-scale assembly pipeline (see csgtile/assembly/assembly.h).

#include "csgtile/assembly/assembly.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <numeric>

#include "csgtile/assembly/broad_phase.h"
#include "csgtile/assembly/voxel_cull.h"
#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "escalation.h"
#include "stacked_model.h"

namespace csgtile::assembly {

namespace {

using Clock = std::chrono::steady_clock;
using kernel::ErrorCode;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Union–find over input indices; the root of a set is its smallest member.
struct Components {
  explicit Components(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int root(int x) {
    while (parent[static_cast<std::size_t>(x)] != x) {
      parent[static_cast<std::size_t>(x)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
      x = parent[static_cast<std::size_t>(x)];
    }
    return x;
  }
  void join(int a, int b) {
    const int ra = root(a), rb = root(b);
    parent[static_cast<std::size_t>(std::max(ra, rb))] = std::min(ra, rb);
  }
  std::vector<int> parent;
};

kernel::Status check_options(const AssemblyOptions& o, std::size_t n) {
  if (!o.anchor.empty() && o.anchor.size() != n) {
    return kernel::Status(ErrorCode::InvalidArgument,
                          "assembly: the anchor rule must mark every primitive");
  }
  if (!(o.voxel_size > 0) || !std::isfinite(o.voxel_size)) {
    return kernel::Status(ErrorCode::InvalidArgument,
                          "assembly: voxel size must be finite and > 0");
  }
  if (!(o.tolerance > 0) || !std::isfinite(o.tolerance)) {
    return kernel::Status(ErrorCode::InvalidArgument, "assembly: tolerance must be finite and > 0");
  }
  if (o.cell) {
    if (!(o.cell->grid.size > 0) || !std::isfinite(o.cell->grid.size)) {
      return kernel::Status(ErrorCode::InvalidArgument,
                            "assembly: cell size must be finite and > 0");
    }
    if (!(o.cell->grid.halo >= 0) || !std::isfinite(o.cell->grid.halo)) {
      return kernel::Status(ErrorCode::InvalidArgument, "assembly: halo must be finite and >= 0");
    }
  }
  return {};
}

// A primitive with a curved face: everything but boxes and extrusions (straight-edged
// profiles, planar clips).
bool is_curved(const kernel::PrimitiveSpec& spec) {
  return spec.type != kernel::PrimitiveType::Box && spec.type != kernel::PrimitiveType::Extrusion;
}

// A candidate pair given the exact test: its verdict, or why the test failed.
struct Tested {
  int a = 0, b = 0;
  std::optional<kernel::Interference> verdict;
  std::string error;
};

// A fused object's compound holds one solid: the result of one Boolean over all its
// primitives (csg_combine fuses a connected group at once), checked by that Boolean.
bool one_solid(const kernel::Shape& compound) {
  return compound.kind() == kernel::ShapeKind::Compound && compound.child_count() == 1 &&
         compound.child(0).kind() == kernel::ShapeKind::Solid;
}

bool within_xy(const kernel::BoundingBox& inner, const kernel::BoundingBox& outer) {
  return inner.min.x() >= outer.min.x() && inner.min.y() >= outer.min.y() &&
         inner.max.x() <= outer.max.x() && inner.max.y() <= outer.max.y();
}

}  // namespace

kernel::Result<Assembly> assemble(const std::vector<AssemblyPrimitive>& primitives,
                                  const AssemblyOptions& options) {
  if (auto s = check_options(options, primitives.size()); !s.ok()) return s.error();
  const auto t_start = Clock::now();
  std::unique_ptr<tbb::global_control> threads;
  if (options.threads > 0) {
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    static_cast<std::size_t>(options.threads));
  }
  Assembly out;
  AssemblyStats& st = out.stats;
  st.primitives = static_cast<long long>(primitives.size());
  kernel::BooleanOptions bopt;
  bopt.tolerance = options.tolerance;
  bopt.interrupt = options.interrupt;
  const auto stopped = [&](const char* stage) {
    return options.interrupt.check(std::string("while ") + stage + " (assembly)");
  };
  // 0. The fuzzy mode: near-coincidences snapped, the snapped primitives assembled.
  std::vector<AssemblyPrimitive> snapped_input;
  if (options.snap.distance > 0.0 || options.snap.angle > 0.0) {
    std::vector<kernel::PrimitiveSpec> specs;
    specs.reserve(primitives.size());
    for (const AssemblyPrimitive& p : primitives) specs.push_back(p.spec);
    auto moved = kernel::snap_primitives(specs, options.snap, &st.snap);
    if (!moved.ok()) return moved.error();
    snapped_input = primitives;
    for (std::size_t i = 0; i < specs.size(); ++i) snapped_input[i].spec = moved.value()[i];
  }
  const std::vector<AssemblyPrimitive>& input = snapped_input.empty() ? primitives : snapped_input;

  // 1. Solids (in parallel; a primitive that cannot be built is reported and left out).
  auto t0 = Clock::now();
  const std::size_t n = primitives.size();
  std::vector<kernel::CsgModel> leaves(n);
  std::vector<std::string> leaf_error(n);
  std::vector<kernel::BoundingBox> boxes(n);  // enlarged by the tolerance
  std::vector<kernel::BoundingBox> exact_boxes(n);
  // Cell region: the cell grown by its halo (XY); a primitive is read when its box meets it.
  std::optional<kernel::BoundingBox> region;
  if (options.cell) region = options.cell->grid.halo_box(options.cell->cell);
  std::vector<char> read(n, 0);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    auto m = kernel::csg_primitive(input[i].spec, input[i].label, options.tolerance);
    if (!m.ok()) {
      leaf_error[i] = m.error().message;
      return;
    }
    const kernel::BoundingBox exact = kernel::bounding_box(m->shape);
    kernel::BoundingBox box = exact;
    box.enlarge(options.tolerance);
    if (region && !region->intersects(box)) return;
    boxes[i] = box;
    exact_boxes[i] = exact;
    leaves[i] = std::move(m).value();
    read[i] = 1;
  });
  for (std::size_t i = 0; i < n; ++i) {
    if (!leaf_error[i].empty()) {
      ++st.primitives_failed;
      out.problems.push_back("primitive " + std::to_string(i) + " (" + primitives[i].label +
                             ") not built: " + leaf_error[i]);
    }
    st.primitives_read += read[i];
  }
  st.seconds_build = seconds_since(t0);
  if (auto s = stopped("building the primitives"); !s.ok()) return s.error();

  // 2. Broad phase: candidate pairs.
  t0 = Clock::now();
  std::vector<std::pair<int, int>> candidates;
  if (options.broad_phase) {
    std::vector<kernel::BoundingBox> live(n);
    for (std::size_t i = 0; i < n; ++i) {
      if (read[i]) live[i] = boxes[i];
    }
    for (const auto& [a, b] : assembly::parallel_overlapping_boxes(live)) {
      candidates.emplace_back(static_cast<int>(a), static_cast<int>(b));
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j) {
        if (read[i] && read[j]) candidates.emplace_back(static_cast<int>(i), static_cast<int>(j));
      }
    }
  }
  st.candidate_pairs = static_cast<long long>(candidates.size());
  st.seconds_broad = seconds_since(t0);

  // 3. OpenVDB culling of candidate pairs, then 4. the exact test of the survivors; a batch
  // at a time (every candidate at once, or rounds outward from the anchored primitives).
  std::vector<kernel::Shape> shapes(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (read[i]) shapes[i] = leaves[i].shape;
  }
  std::vector<Tested> tested;
  bool culling_skipped = false;
  const auto test_pairs = [&](const std::vector<std::pair<int, int>>& batch) -> kernel::Status {
    auto t_batch = Clock::now();
    std::vector<std::pair<int, int>> survivors;
    if (options.voxel_culling && !batch.empty()) {
      // Voxels pay where the exact test costs more than the two shells: pairs with a curved
      // solid, or whose face counts multiply to voxel_min_face_product or more. Other pairs
      // (two boxes, a box and an L-shaped prism) go straight to the exact test; pairs whose
      // boxes do not meet (without the broad phase) are dropped here.
      std::vector<char> keep(batch.size(), 0);
      std::vector<std::size_t> costly;  // into batch
      for (std::size_t k = 0; k < batch.size(); ++k) {
        const auto a = static_cast<std::size_t>(batch[k].first),
                   b = static_cast<std::size_t>(batch[k].second);
        if (!boxes[a].intersects(boxes[b])) continue;
        const bool curved = is_curved(primitives[a].spec) || is_curved(primitives[b].spec);
        const double faces = static_cast<double>(leaves[a].face_sources.size()) *
                             static_cast<double>(leaves[b].face_sources.size());
        if (curved || faces >= options.voxel_min_face_product) {
          costly.push_back(k);
        } else {
          keep[k] = 1;
        }
      }
      if (!costly.empty()) {
        std::vector<std::pair<int, int>> pairs;
        for (std::size_t k : costly) pairs.push_back(batch[k]);
        VoxelCuller culler(options.voxel_size, options.tolerance);
        culler.build(shapes, pairs, &exact_boxes);
        if (!culler.unavailable().empty() && !culling_skipped) {
          culling_skipped = true;
          out.problems.push_back("voxel culling skipped (every candidate pair tested exactly): " +
                                 culler.unavailable());
        }
        for (std::size_t i = 0; i < n; ++i) st.active_voxels += culler.active_voxels(i);
        tbb::parallel_for(std::size_t{0}, pairs.size(), [&](std::size_t c) {
          keep[costly[c]] = culler.may_meet(static_cast<std::size_t>(pairs[c].first),
                                            static_cast<std::size_t>(pairs[c].second));
        });
      }
      for (std::size_t k = 0; k < batch.size(); ++k) {
        if (keep[k]) survivors.push_back(batch[k]);
      }
    } else {
      survivors = batch;
    }
    if (auto s = stopped("culling pairs"); !s.ok()) return s;
    st.culled_pairs += static_cast<long long>(batch.size() - survivors.size());
    st.seconds_voxel += seconds_since(t_batch);

    t_batch = Clock::now();
    st.exact_tests += static_cast<long long>(survivors.size());
    const std::size_t first = tested.size();
    tested.resize(first + survivors.size());
    tbb::parallel_for(std::size_t{0}, survivors.size(), [&](std::size_t k) {
      Tested& t = tested[first + k];
      std::tie(t.a, t.b) = survivors[k];
      auto r = kernel::solid_interference(shapes[static_cast<std::size_t>(t.a)],
                                          shapes[static_cast<std::size_t>(t.b)], bopt);
      if (r.ok()) {
        t.verdict = r.value();
      } else {
        t.error = r.error().message;
      }
    });
    st.seconds_exact += seconds_since(t_batch);
    // A test the interrupt cut short decided nothing: the assembly stops as a whole.
    return stopped("testing pairs");
  };
  const auto same_object = [&](const Tested& t) {
    return !(t.verdict && *t.verdict == kernel::Interference::Disjoint) &&
           primitives[static_cast<std::size_t>(t.a)].group ==
               primitives[static_cast<std::size_t>(t.b)].group;
  };
  // The primitives whose objects are found: all read ones, or those the rounds reach.
  std::vector<char> reached = options.anchor.empty() ? read : std::vector<char>(n, 0);
  if (options.anchor.empty()) {
    if (auto s = test_pairs(candidates); !s.ok()) return s.error();
  } else {
    // Rounds outward from the primitives anchored in the cell along contacts within a group.
    // A primitive anchored before the cell ends its round: its object is another cell's, and
    // every path from the cell's primitives to it reaches it.
    std::vector<std::vector<std::size_t>> incident(n);
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      incident[static_cast<std::size_t>(candidates[k].first)].push_back(k);
      incident[static_cast<std::size_t>(candidates[k].second)].push_back(k);
    }
    std::vector<char> done(candidates.size(), 0);
    std::vector<int> frontier;
    for (std::size_t i = 0; i < n; ++i) {
      if (read[i] && options.anchor[i] == 0) {
        reached[i] = 1;
        frontier.push_back(static_cast<int>(i));
      }
    }
    while (!frontier.empty()) {
      std::vector<std::pair<int, int>> batch;
      for (int v : frontier) {
        for (std::size_t k : incident[static_cast<std::size_t>(v)]) {
          if (!done[k]) {
            done[k] = 1;
            batch.push_back(candidates[k]);
          }
        }
      }
      std::sort(batch.begin(), batch.end());
      const std::size_t first = tested.size();
      if (auto s = test_pairs(batch); !s.ok()) return s.error();
      frontier.clear();
      for (std::size_t k = first; k < tested.size(); ++k) {
        if (!same_object(tested[k])) continue;
        for (int v : {tested[k].a, tested[k].b}) {
          if (reached[static_cast<std::size_t>(v)]) continue;
          reached[static_cast<std::size_t>(v)] = 1;
          if (options.anchor[static_cast<std::size_t>(v)] >= 0) frontier.push_back(v);
        }
      }
      std::sort(frontier.begin(), frontier.end());
    }
  }

  // Components of the contact graph are the objects.
  auto t0c = Clock::now();
  Components comps(n);
  std::vector<Contact> contacts;
  for (const Tested& t : tested) {
    if (t.verdict && *t.verdict == kernel::Interference::Disjoint) continue;
    // A pair the exact test could not decide is kept together (the fuse decides or fails with
    // a reason) rather than published as two objects that may overlap.
    contacts.push_back({t.a, t.b, t.verdict.value_or(kernel::Interference::BoundariesMeet)});
    if (!t.verdict) {
      out.problems.push_back("pair " + primitives[static_cast<std::size_t>(t.a)].label + " / " +
                             primitives[static_cast<std::size_t>(t.b)].label +
                             ": exact test failed, assumed in contact: " + t.error);
    }
    // Two groups' contact is a relation between objects, never one object.
    if (same_object(t)) comps.join(t.a, t.b);
  }
  st.interacting_pairs = static_cast<long long>(contacts.size());
  std::map<int, std::vector<int>> members;
  for (std::size_t i = 0; i < n; ++i) {
    if (reached[i]) members[comps.root(static_cast<int>(i))].push_back(static_cast<int>(i));
  }
  st.components = static_cast<long long>(members.size());
  st.seconds_exact += seconds_since(t0c);

  // 5. Anchor rule, then one n-ary fuse per kept object (in parallel).
  t0 = Clock::now();
  std::vector<std::vector<int>> groups;
  std::vector<kernel::BoundingBox> group_boxes;
  std::vector<char> past_halo;
  for (auto& [root, list] : members) {
    kernel::BoundingBox box;
    for (int i : list) box.add(exact_boxes[static_cast<std::size_t>(i)]);
    if (options.cell) {
      if (options.cell->grid.cell_of(box.min.x(), box.min.y()) != options.cell->cell) continue;
    }
    if (!options.anchor.empty()) {
      int least = 1;
      for (int i : list) least = std::min(least, options.anchor[static_cast<std::size_t>(i)]);
      if (least != 0) continue;
    }
    groups.push_back(list);
    group_boxes.push_back(box);
    past_halo.push_back(region && !within_xy(box, *region));
  }
  out.objects.resize(groups.size());
  tbb::parallel_for(std::size_t{0}, groups.size(), [&](std::size_t g) {
    AssembledObject& o = out.objects[g];
    o.primitives = groups[g];
    o.group = primitives[static_cast<std::size_t>(groups[g].front())].group;
    o.id = "obj-" + primitives[static_cast<std::size_t>(groups[g].front())].label;
    o.reaches_past_halo = past_halo[g] != 0;
    if (groups[g].size() == 1) {
      // A single primitive: its own tree; its solid in a compound like every object's (the
      // compound lists the solid's faces in the same order, so the sources carry over).
      o.model = leaves[static_cast<std::size_t>(groups[g].front())];
      auto compound = kernel::ShapeFactory::compound({o.model.shape});
      if (compound.ok()) o.model.shape = compound.value();
    } else {
      std::vector<kernel::CsgModel> parts;
      for (int i : groups[g]) parts.push_back(leaves[static_cast<std::size_t>(i)]);
      // The object's own time limit, from when its fuse starts.
      kernel::BooleanOptions object_options = bopt;
      object_options.interrupt = options.interrupt.within(options.object_time_limit);
      auto fused = kernel::csg_combine(parts, kernel::BooleanOp::Fuse, object_options);
      const bool cancelled = !fused.ok() && fused.error().code == ErrorCode::Cancelled;
      std::optional<detail::Escalated> escalated;
      const bool escalate = !fused.ok() && !cancelled && options.escalate_to > 0.0;
      if (escalate) {
        std::vector<AssemblyPrimitive> group;
        for (int i : groups[g]) group.push_back(primitives[static_cast<std::size_t>(i)]);
        escalated = detail::escalate_fuse(group, options, object_options.interrupt);
      }
      if (fused.ok()) {
        o.model = std::move(fused).value();
        o.checked = one_solid(o.model.shape);
      } else if (escalated) {
        o.model = std::move(escalated->model);
        o.checked = one_solid(o.model.shape);
        o.escalation = AssembledObject::Escalation{escalated->snap, fused.error().message};
      } else {
        o.fused = false;
        o.error = fused.error().message;
        // Escalation stops where the limit is reached too: its last fuse's error is the same.
        o.timed_out = cancelled || (escalate && object_options.interrupt.fired());
        if (o.timed_out && !cancelled) {
          o.error = object_options.interrupt.error("while escalating").message +
                    " (first: " + o.error + ")";
        }
        std::vector<const kernel::CsgModel*> ptrs;
        for (const auto& p : parts) ptrs.push_back(&p);
        auto stacked = detail::stacked_model(ptrs);
        if (stacked.ok()) o.model = std::move(stacked).value();
      }
    }
    // A lone primitive's box is its leaf's (the compound holds the same faces and edges).
    o.box = groups[g].size() == 1 ? exact_boxes[static_cast<std::size_t>(groups[g].front())]
                                  : kernel::bounding_box(o.model.shape);
    o.volume = kernel::shape_volume(o.model.shape);
  });
  // Objects cut short by the assembly's own interrupt (not their time limit) are not results.
  if (auto s = stopped("fusing objects"); !s.ok()) return s.error();
  std::vector<char> published(n, 0);
  for (const AssembledObject& o : out.objects) {
    for (int i : o.primitives) published[static_cast<std::size_t>(i)] = 1;
    if (o.escalation) ++st.objects_escalated;
    if (o.timed_out) ++st.objects_timed_out;
    if (!o.fused) {
      ++st.objects_failed;
      out.problems.push_back("object " + o.id + " not fused: " + o.error);
    }
    if (o.reaches_past_halo) {
      ++st.objects_past_halo;
      out.problems.push_back("object " + o.id +
                             " reaches past the halo: widen the halo or the cell");
    }
  }
  for (const Contact& c : contacts) {
    if (published[static_cast<std::size_t>(c.a)]) out.contacts.push_back(c);
  }
  std::sort(out.contacts.begin(), out.contacts.end(), [](const Contact& x, const Contact& y) {
    return std::tie(x.a, x.b) < std::tie(y.a, y.b);
  });
  st.objects = static_cast<long long>(out.objects.size());
  st.seconds_fuse = seconds_since(t0);
  st.seconds_total = seconds_since(t_start);
  return out;
}

kernel::Result<kernel::CsgModel> city_model(const std::vector<AssembledObject>& objects) {
  std::vector<const kernel::CsgModel*> models;
  for (const AssembledObject& o : objects) models.push_back(&o.model);
  if (models.empty()) {
    kernel::CsgModel empty;
    auto compound = kernel::ShapeFactory::compound({});
    if (!compound.ok()) return compound.error();
    empty.shape = compound.value();
    return empty;
  }
  auto model = detail::stacked_model(models);
  if (!model.ok()) return model;
  if (auto s = kernel::check_csg(model.value()); !s.ok()) return s.error();
  return model;
}

}  // namespace csgtile::assembly
