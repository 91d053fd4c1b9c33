// Polygons of a labelled grid whose neighbours share their boundaries exactly (partition.h).
//
// The boundaries between components are a planar graph on the grid's vertices: its nodes
// are the vertices where three or more boundary edges meet (and two chosen vertices on each
// loop that has none), its chains the runs of boundary edges between nodes. Each chain is
// simplified once; the components' rings, traced with the component on the left, are
// written with the simplified chains. All coordinates stay grid vertices (integers), so the
// crossing tests are exact.

#include "partition.h"

#include "csgtile/kernel/polygon2d.h"
#include "plane2d.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <unordered_map>

namespace csgtile::fit::detail {

namespace {

using P = kernel::GridVertex;

// The chain's vertices without those collinear with their neighbours (ends kept).
std::vector<P> without_collinear(const std::vector<P>& v) {
  std::vector<P> out{v.front()};
  for (std::size_t k = 1; k + 1 < v.size(); ++k) {
    if (kernel::grid_orientation(out.back(), v[k], v[k + 1]) != 0) out.push_back(v[k]);
  }
  out.push_back(v.back());
  return out;
}

struct Chain {
  std::vector<P> raw;         // cell-edge vertices, node to node
  std::vector<P> simplified;  // the polyline used by the rings
};

}  // namespace

void close_cells(std::vector<char>& occupied, int nx, int ny) {
  auto pass = [&](bool dilate) {
    std::vector<char> next = occupied;
    for (int j = 1; j + 1 < ny; ++j) {
      for (int i = 1; i + 1 < nx; ++i) {
        bool any = false, all = true;
        for (int dj = -1; dj <= 1; ++dj) {
          for (int di = -1; di <= 1; ++di) {
            const bool m =
                occupied[static_cast<std::size_t>(j + dj) * static_cast<std::size_t>(nx) +
                         static_cast<std::size_t>(i + di)] != 0;
            any = any || m;
            all = all && m;
          }
        }
        next[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
             static_cast<std::size_t>(i)] = dilate ? any : all;
      }
    }
    occupied = std::move(next);
  };
  pass(true);
  pass(false);
}

Components label_components(const LabelGrid& grid) {
  Components c;
  c.of.assign(grid.label.size(), -1);
  for (int j = 0; j < grid.ny; ++j) {
    for (int i = 0; i < grid.nx; ++i) {
      const auto start = static_cast<std::size_t>(j) * static_cast<std::size_t>(grid.nx) +
                         static_cast<std::size_t>(i);
      const int l = grid.label[start];
      if (l < 0 || c.of[start] >= 0) continue;
      std::vector<std::array<int, 2>> queue{{i, j}};
      c.of[start] = c.count;
      for (std::size_t h = 0; h < queue.size(); ++h) {
        const auto [ci, cj] = queue[h];
        const std::array<std::array<int, 2>, 4> nb{
            {{ci + 1, cj}, {ci - 1, cj}, {ci, cj + 1}, {ci, cj - 1}}};
        for (const auto& q : nb) {
          if (grid.at(q[0], q[1]) != l) continue;
          const auto k = static_cast<std::size_t>(q[1]) * static_cast<std::size_t>(grid.nx) +
                         static_cast<std::size_t>(q[0]);
          if (c.of[k] >= 0) continue;
          c.of[k] = c.count;
          queue.push_back(q);
        }
      }
      ++c.count;
    }
  }
  return c;
}

int unpinch(LabelGrid& grid) {
  int changed = 0;
  for (int pass = 0; pass < 64; ++pass) {
    int now = 0;
    for (int j = -1; j < grid.ny; ++j) {
      for (int i = -1; i < grid.nx; ++i) {
        // Block of cells p = (i, j), q = (i+1, j), r = (i, j+1), s = (i+1, j+1).
        const int p = grid.at(i, j), q = grid.at(i + 1, j), r = grid.at(i, j + 1),
                  s = grid.at(i + 1, j + 1);
        const bool ps = p == s && q != p && r != p;
        const bool qr = q == r && p != q && s != q;
        const bool four = p != q && p != r && p != s && q != r && q != s && r != s;
        if (!ps && !qr && !four) continue;
        auto set = [&](int ci, int cj, int l) {
          if (l < 0 && !(ps || qr)) return false;
          if (ci < 0 || cj < 0 || ci >= grid.nx || cj >= grid.ny) return false;
          grid.cell(ci, cj) = l;
          return true;
        };
        bool done = false;
        if (four) {
          // A cell takes the label of a neighbour in the block: three parts meet (a T).
          done = set(i + 1, j, p) || set(i, j + 1, p) || set(i, j, q) || set(i + 1, j + 1, q) ||
                 set(i, j, r) || set(i + 1, j + 1, r) || set(i + 1, j, s) || set(i, j + 1, s);
        }
        if (ps && p >= 0) done = set(i + 1, j, p) || set(i, j + 1, p);
        if (!done && qr && q >= 0) done = set(i, j, q) || set(i + 1, j + 1, q);
        if (!done && ps) done = set(i, j, q >= 0 ? q : r) || set(i + 1, j + 1, q >= 0 ? q : r);
        if (!done && qr) done = set(i + 1, j, p >= 0 ? p : s) || set(i, j + 1, p >= 0 ? p : s);
        now += done ? 1 : 0;
      }
    }
    changed += now;
    if (now == 0) break;
  }
  return changed;
}

std::vector<PartPolygon> partition_polygons(const LabelGrid& grid, double tolerance) {
  const Components comp = label_components(grid);
  std::vector<PartPolygon> parts(static_cast<std::size_t>(comp.count));
  if (comp.count == 0) return parts;
  const int nx = grid.nx, ny = grid.ny;
  // Vertex ids are packed two to a 64-bit key.
  if ((static_cast<double>(nx) + 1.0) * (static_cast<double>(ny) + 1.0) >= 4294967296.0) {
    return parts;
  }
  auto comp_at = [&](int i, int j) {
    if (i < 0 || j < 0 || i >= nx || j >= ny) return -1;
    return comp.of[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
                   static_cast<std::size_t>(i)];
  };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int k = comp_at(i, j);
      if (k < 0) continue;
      auto& part = parts[static_cast<std::size_t>(k)];
      part.label = grid.at(i, j);
      part.cells.push_back(j * nx + i);
    }
  }
  auto vid = [&](const P& p) { return p[1] * (nx + 1) + p[0]; };
  // Undirected boundary edges and each boundary vertex's edges.
  std::vector<std::array<P, 2>> edges;
  std::vector<std::set<int>> next_to(parts.size());
  auto boundary = [&](int x, int y, const P& a, const P& b) {
    if (x == y) return;
    edges.push_back({a, b});
    if (x >= 0 && y >= 0) {
      next_to[static_cast<std::size_t>(x)].insert(y);
      next_to[static_cast<std::size_t>(y)].insert(x);
    }
  };
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      if (j < ny) boundary(comp_at(i - 1, j), comp_at(i, j), P{i, j}, P{i, j + 1});
      if (i < nx) boundary(comp_at(i, j - 1), comp_at(i, j), P{i, j}, P{i + 1, j});
    }
  }
  for (std::size_t k = 0; k < parts.size(); ++k) {
    parts[k].neighbours.assign(next_to[k].begin(), next_to[k].end());
  }
  std::unordered_map<long long, std::vector<std::size_t>> at_vertex;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    at_vertex[vid(edges[e][0])].push_back(e);
    at_vertex[vid(edges[e][1])].push_back(e);
  }
  std::set<long long> nodes;
  for (const auto& e : edges) {
    for (const auto& v : e) {
      if (at_vertex[vid(v)].size() != 2) nodes.insert(vid(v));
    }
  }
  // Chains from node to node; loops without a node get two (their start and their middle).
  std::vector<Chain> chains;
  std::vector<char> visited(edges.size(), 0);
  auto other = [&](std::size_t e, const P& v) {
    return edges[e][0] == v ? edges[e][1] : edges[e][0];
  };
  auto walk = [&](const P& start, std::size_t e) {
    Chain c;
    c.raw.push_back(start);
    P cur = other(e, start);
    visited[e] = 1;
    while (nodes.count(vid(cur)) == 0) {
      c.raw.push_back(cur);
      std::size_t next = edges.size();
      for (auto f : at_vertex[vid(cur)]) {
        if (!visited[f]) next = f;
      }
      if (next == edges.size()) break;  // cannot happen on a closed boundary
      visited[next] = 1;
      cur = other(next, cur);
    }
    c.raw.push_back(cur);
    chains.push_back(std::move(c));
  };
  {
    // Runs of degree-2 vertices are paths between nodes or loops; a walk stops at a node or
    // at an edge an earlier walk took (whose run is known to have a node, or got two).
    std::vector<char> seen(edges.size(), 0);
    for (std::size_t e = 0; e < edges.size(); ++e) {
      if (seen[e]) continue;
      seen[e] = 1;
      std::vector<P> loop{edges[e][0]};
      P cur = edges[e][1];
      std::size_t came = e;
      bool closed = false;
      while (nodes.count(vid(loop.front())) == 0 && nodes.count(vid(cur)) == 0) {
        if (cur == loop.front()) {
          closed = true;
          break;
        }
        loop.push_back(cur);
        std::size_t next = came;
        for (auto f : at_vertex[vid(cur)]) {
          if (f != came) next = f;
        }
        if (next == came || seen[next]) break;
        seen[next] = 1;
        came = next;
        cur = other(next, cur);
      }
      if (closed) {
        nodes.insert(vid(loop.front()));
        nodes.insert(vid(loop[loop.size() / 2]));
      }
    }
  }
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (visited[e]) continue;
    const P start = nodes.count(vid(edges[e][0])) != 0 ? edges[e][0] : edges[e][1];
    if (nodes.count(vid(start)) == 0) continue;  // reached from a node below
    walk(start, e);
  }
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (visited[e]) continue;  // interior edges of chains not started at a node: none expected
    walk(edges[e][0], e);
  }
  // The chain and direction of each directed first step.
  std::unordered_map<std::uint64_t, std::pair<std::size_t, bool>> step;
  auto key = [&](const P& a, const P& b) {
    return (static_cast<std::uint64_t>(vid(a)) << 32) ^ static_cast<std::uint64_t>(vid(b));
  };
  for (std::size_t c = 0; c < chains.size(); ++c) {
    const auto& r = chains[c].raw;
    step[key(r[0], r[1])] = {c, true};
    step[key(r[r.size() - 1], r[r.size() - 2])] = {c, false};
  }
  // Rings of each component as cycles of grid vertices, the component on the left; at a
  // vertex with a choice (none after unpinch) the trace turns left.
  struct DEdge {
    P a, b;
    int comp;
  };
  std::vector<DEdge> directed;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int k = comp_at(i, j);
      if (k < 0) continue;
      if (comp_at(i, j - 1) != k) directed.push_back({P{i, j}, P{i + 1, j}, k});
      if (comp_at(i + 1, j) != k) directed.push_back({P{i + 1, j}, P{i + 1, j + 1}, k});
      if (comp_at(i, j + 1) != k) directed.push_back({P{i + 1, j + 1}, P{i, j + 1}, k});
      if (comp_at(i - 1, j) != k) directed.push_back({P{i, j + 1}, P{i, j}, k});
    }
  }
  std::map<std::pair<int, long long>, std::vector<std::size_t>> from;
  for (std::size_t e = 0; e < directed.size(); ++e) {
    from[{directed[e].comp, vid(directed[e].a)}].push_back(e);
  }
  std::vector<char> done(directed.size(), 0);
  struct Cycle {
    int comp;
    std::vector<P> v;
  };
  std::vector<Cycle> cycles;
  for (std::size_t first = 0; first < directed.size(); ++first) {
    if (done[first]) continue;
    Cycle cyc{directed[first].comp, {}};
    std::size_t e = first;
    for (;;) {
      done[e] = 1;
      cyc.v.push_back(directed[e].a);
      const auto& out = from[{cyc.comp, vid(directed[e].b)}];
      std::size_t next = directed.size();
      const long long dx = directed[e].b[0] - directed[e].a[0],
                      dy = directed[e].b[1] - directed[e].a[1];
      long long best = -2;
      for (auto k : out) {
        if (done[k]) continue;
        const long long ex = directed[k].b[0] - directed[k].a[0],
                        ey = directed[k].b[1] - directed[k].a[1];
        const long long turn = dx * ey - dy * ex;
        if (turn > best) {
          best = turn;
          next = k;
        }
      }
      if (next == directed.size()) break;
      e = next;
    }
    cycles.push_back(std::move(cyc));
  }
  // Rings of a cycle from the chains (simplified or raw).
  auto ring_of = [&](const Cycle& cyc) {
    std::vector<P> ring;
    const std::size_t n = cyc.v.size();
    std::size_t s = 0;
    while (s < n && nodes.count(vid(cyc.v[s])) == 0) ++s;
    if (s == n) return ring;
    std::size_t walked = 0;
    while (walked < n) {
      const P& a = cyc.v[(s + walked) % n];
      const P& b = cyc.v[(s + walked + 1) % n];
      const auto it = step.find(key(a, b));
      if (it == step.end()) return std::vector<P>{};
      const Chain& c = chains[it->second.first];
      const auto& poly = c.simplified;
      if (it->second.second) {
        ring.insert(ring.end(), poly.begin(), poly.end() - 1);
      } else {
        ring.insert(ring.end(), poly.rbegin(), poly.rend() - 1);
      }
      walked += c.raw.size() - 1;
    }
    return ring;
  };
  // Simplify every chain, then undo the simplification of chains that cross, and of the
  // chains around a part whose rings turned the wrong way or lost a hole, until none is left.
  std::vector<char> raw_only(chains.size(), 0);
  for (std::size_t c = 0; c < chains.size(); ++c) {
    std::vector<Vec2> at;  // grid vertices are small integers: exact as doubles
    for (const P& q : chains[c].raw) {
      at.emplace_back(static_cast<double>(q[0]), static_cast<double>(q[1]));
    }
    std::vector<char> keep(chains[c].raw.size(), 0);
    keep.front() = keep.back() = 1;
    douglas_peucker(at, 0, at.size() - 1, tolerance, keep);
    for (std::size_t k = 0; k < keep.size(); ++k) {
      if (keep[k]) chains[c].simplified.push_back(chains[c].raw[k]);
    }
  }
  std::vector<std::vector<std::size_t>> chains_of_cycle(cycles.size());
  for (std::size_t y = 0; y < cycles.size(); ++y) {
    const auto& v = cycles[y].v;
    for (std::size_t k = 0; k < v.size(); ++k) {
      const auto it = step.find(key(v[k], v[(k + 1) % v.size()]));
      if (it != step.end()) chains_of_cycle[y].push_back(it->second.first);
    }
  }
  for (int round = 0; round < 64; ++round) {
    std::set<std::size_t> bad;
    // Crossings between segments, found through a bucket grid of 8 × 8 cells.
    struct Seg {
      P a, b;
      std::size_t chain;
    };
    std::vector<Seg> segs;
    for (std::size_t c = 0; c < chains.size(); ++c) {
      const auto& s = chains[c].simplified;
      for (std::size_t k = 0; k + 1 < s.size(); ++k) segs.push_back({s[k], s[k + 1], c});
    }
    std::map<std::pair<long long, long long>, std::vector<std::size_t>> bucket;
    for (std::size_t g = 0; g < segs.size(); ++g) {
      const long long x0 = std::min(segs[g].a[0], segs[g].b[0]) / 8,
                      x1 = std::max(segs[g].a[0], segs[g].b[0]) / 8,
                      y0 = std::min(segs[g].a[1], segs[g].b[1]) / 8,
                      y1 = std::max(segs[g].a[1], segs[g].b[1]) / 8;
      for (long long by = y0; by <= y1; ++by) {
        for (long long bx = x0; bx <= x1; ++bx) bucket[{bx, by}].push_back(g);
      }
    }
    std::set<std::pair<std::size_t, std::size_t>> tested;
    for (const auto& [unused, list] : bucket) {
      for (std::size_t x = 0; x < list.size(); ++x) {
        for (std::size_t y = x + 1; y < list.size(); ++y) {
          const Seg& s = segs[list[x]];
          const Seg& t = segs[list[y]];
          if (raw_only[s.chain] && raw_only[t.chain]) continue;  // cell edges never cross
          if (!tested.insert({list[x], list[y]}).second) continue;
          if (kernel::grid_segments_conflict(s.a, s.b, t.a, t.b)) {
            if (!raw_only[s.chain]) bad.insert(s.chain);
            if (!raw_only[t.chain]) bad.insert(t.chain);
          }
        }
      }
    }
    // Rings: each keeps its orientation; each hole stays inside its part's outer ring.
    if (bad.empty()) {
      std::vector<std::vector<std::size_t>> cycles_of(parts.size());
      for (std::size_t y = 0; y < cycles.size(); ++y) {
        cycles_of[static_cast<std::size_t>(cycles[y].comp)].push_back(y);
      }
      for (std::size_t k = 0; k < parts.size(); ++k) {
        std::vector<std::vector<P>> rings;
        bool ok = true;
        std::size_t outer = 0;
        long long outer_area = 0, raw_total = 0, total = 0;
        for (auto y : cycles_of[k]) {
          auto ring = ring_of(cycles[y]);
          const long long raw_area = kernel::grid_ring_area2(cycles[y].v);
          const long long area = ring.size() >= 3 ? kernel::grid_ring_area2(ring) : 0;
          ok = ok && area != 0 && (area > 0) == (raw_area > 0);
          raw_total += raw_area;
          total += area;
          if (area > outer_area) {
            outer_area = area;
            outer = rings.size();
          }
          rings.push_back(std::move(ring));
        }
        // A part keeps three quarters of its area at least (a small part is not cut down to
        // a sliver; a staircase along a diagonal loses up to half a cell along it).
        ok = ok && 4 * std::abs(total - raw_total) < raw_total;
        for (std::size_t r = 0; ok && r < rings.size(); ++r) {
          if (r == outer) continue;
          ok = kernel::grid_midpoint_inside(rings[r][0], rings[r][1], rings[outer]);
        }
        if (!ok) {
          for (auto y : cycles_of[k]) {
            for (auto c : chains_of_cycle[y]) {
              if (!raw_only[c]) bad.insert(c);
            }
          }
        }
      }
    }
    if (bad.empty()) break;
    if (round == 63) {  // out of rounds: every chain keeps its cell edges
      for (std::size_t c = 0; c < chains.size(); ++c) bad.insert(c);
    }
    for (auto c : bad) {
      raw_only[c] = 1;
      chains[c].simplified = without_collinear(chains[c].raw);
    }
  }
  for (const auto& cyc : cycles) {
    const auto ring = ring_of(cyc);
    if (ring.size() < 3) continue;
    std::vector<Eigen::Vector2d> r;
    for (const auto& p : ring) {
      r.emplace_back(static_cast<double>(p[0]), static_cast<double>(p[1]));
    }
    auto& part = parts[static_cast<std::size_t>(cyc.comp)];
    // One counter-clockwise ring per 4-connected part: its outline; the others are holes.
    if (kernel::grid_ring_area2(ring) > 0 && part.outer.empty()) {
      part.outer = std::move(r);
    } else {
      part.holes.push_back(std::move(r));
    }
  }
  return parts;
}

}  // namespace csgtile::fit::detail
