#include "micro/netting/lacing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

namespace gabion::micro {
namespace {

double median(std::vector<double> v) {
  const std::size_t h = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h), v.end());
  if (v.size() % 2 == 1) return v[h];
  const double upper = v[h];
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h)));
}

}  // namespace

CellEdges cellEdges(const Scene& cell, double band_m) {
  if (!(band_m > 0.0)) throw std::invalid_argument("cellEdges: the band must be > 0");
  CellEdges out;
  out.band_m = band_m;
  out.faces.assign(cell.spheres.size(), 0);
  std::vector<std::size_t> nodes;
  {
    std::vector<bool> is_node(cell.spheres.size(), false);
    for (const LinkSpec& l : cell.links) {
      if (l.a < is_node.size()) is_node[l.a] = true;
      if (l.b < is_node.size()) is_node[l.b] = true;
    }
    for (std::size_t k = 0; k < is_node.size(); ++k)
      if (is_node[k]) nodes.push_back(k);
  }
  if (nodes.empty()) return out;
  // Start from the nodes' extent, then each plane at the median of the
  // nodes nearest to it, until the assignment stands (a few rounds).
  for (int a = 0; a < 3; ++a) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const std::size_t k : nodes)
      lo = std::min(lo, cell.spheres[k].center_m[a]), hi = std::max(hi, cell.spheres[k].center_m[a]);
    out.plane[static_cast<std::size_t>(faceIndex(a, 0))] = lo;
    out.plane[static_cast<std::size_t>(faceIndex(a, 1))] = hi;
  }
  const auto distance = [&](std::size_t k, int f) {
    return std::fabs(cell.spheres[k].center_m[f % 3] - out.plane[static_cast<std::size_t>(f)]);
  };
  std::vector<int> nearest(nodes.size(), -1);
  for (int round = 0; round < 20; ++round) {
    bool changed = false;
    std::array<std::vector<double>, 6> members;
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      int best = 0;
      for (int f = 1; f < 6; ++f)
        if (distance(nodes[n], f) < distance(nodes[n], best)) best = f;
      changed |= best != nearest[n];
      nearest[n] = best;
      members[static_cast<std::size_t>(best)].push_back(cell.spheres[nodes[n]].center_m[best % 3]);
    }
    if (!changed) break;
    for (int f = 0; f < 6; ++f)
      if (!members[static_cast<std::size_t>(f)].empty())
        out.plane[static_cast<std::size_t>(f)] = median(members[static_cast<std::size_t>(f)]);
  }
  for (const std::size_t k : nodes)
    for (int f = 0; f < 6; ++f)
      if (distance(k, f) <= band_m) out.faces[k] |= static_cast<std::uint8_t>(1u << f);
  return out;
}

namespace {
bridge::WireCurve wireCurveOf(const LacingParams& params) {
  return bridge::wireCurve(params.table, params.wire_diameter_m);
}

// A lacing wire between spheres a and b, `distance` apart (m): the
// netting's wire law at the lacing wire's diameter (`curve`), its rest
// length the distance but at least params.min_length_m, pulled tight
// where params.pull_N says.
LinkSpec lacingWire(std::size_t a, std::size_t b, double distance, const LacingParams& params,
                    const bridge::WireCurve& curve) {
  LinkSpec l;
  l.a = a;
  l.b = b;
  l.law = LinkSpec::Law::Wire;
  l.wire.curve = curve;
  l.wire.rest_length_m = std::max(distance, params.min_length_m);
  if (params.pull_N > 0.0 && params.min_length_m > 0.0)
    l.pull_force_N = params.pull_N, l.pull_min_m = params.min_length_m;
  return l;
}

// Pairs points of a with points of b within max_gap_m of each other,
// nearest first, each point in one pair at most, ties in index order: the
// lacing's rule, for two cells' faces and for a face and its neighbour's
// stand-in alike. Returns (distance, index in a, index in b).
std::vector<std::tuple<double, std::size_t, std::size_t>> nearestPairs(const std::vector<Vec3>& a,
                                                                       const std::vector<Vec3>& b, double max_gap_m) {
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs, out;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) {
      const double d = (a[i] - b[j]).norm();
      if (d <= max_gap_m && d > 0.0) pairs.emplace_back(d, i, j);
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  for (const auto& [d, i, j] : pairs) {
    if (used_a[i] || used_b[j]) continue;
    used_a[i] = used_b[j] = true;
    out.emplace_back(d, i, j);
  }
  return out;
}

// An anchor for a lacing wire: a fixed sphere like `node`, at `at`, that
// rides plate `wall` and touches nothing (contact group `group`).
SphereSpec plateAnchor(const SphereSpec& node, const Vec3& at, std::size_t wall, int group) {
  SphereSpec anchor;
  anchor.center_m = at;
  anchor.radius_m = node.radius_m;
  anchor.material = node.material;
  anchor.fixed = true;
  anchor.group = group;
  anchor.rides_wall = static_cast<int>(wall);
  return anchor;
}

void checkPlate(const Scene& scene, const CellEdges& edges, std::size_t first, int face, std::size_t wall,
                const char* who) {
  if (face < 0 || face > 5) throw std::invalid_argument(std::string(who) + ": faces are 0 .. 5");
  if (first + edges.faces.size() > scene.spheres.size())
    throw std::invalid_argument(std::string(who) + ": the cell's spheres run past the scene's");
  if (wall >= scene.walls.size() || !scene.walls[wall].bounded)
    throw std::invalid_argument(std::string(who) + ": the plate must be a bounded wall of the scene");
}
}  // namespace

LacedPlate lacePlate(Scene& scene, const CellEdges& edges, std::size_t first, int face, std::size_t wall,
                     int anchor_group, const LacingParams& params, std::vector<bool>& taken) {
  const std::size_t n = edges.faces.size();
  checkPlate(scene, edges, first, face, wall, "lacePlate");
  taken.resize(n, false);
  const WallSpec& plate = scene.walls[wall];
  const Vec3 nrm = plate.normal, u = plate.axis_u, v = nrm.cross(u);
  const bridge::WireCurve curve = wireCurveOf(params);
  LacedPlate out;
  for (std::size_t k = 0; k < n; ++k) {
    if (taken[k] || !edges.onEdgeOf(k, face)) continue;
    const SphereSpec& node = scene.spheres[first + k];
    const Vec3 rel = node.center_m - plate.point_m;
    if (std::fabs(rel.dot(u)) > plate.half_u_m || std::fabs(rel.dot(v)) > plate.half_v_m) continue;
    taken[k] = true;
    // (the plate's normal points into the cell: the neighbour's node stands
    // behind the plate, a node radius past it)
    const double gap = rel.dot(nrm) + node.radius_m;
    if (!(gap > 0.0 && gap <= params.max_gap_m)) {  // (too far, or through the plate)
      ++out.unlaced;
      continue;
    }
    const SphereSpec anchor = plateAnchor(node, node.center_m - gap * nrm, wall, anchor_group);
    scene.links.push_back(lacingWire(first + k, scene.spheres.size(), gap, params, curve));
    scene.spheres.push_back(anchor);
    ++out.links;
  }
  return out;
}

LacedPlate lacePlateAsNeighbour(Scene& scene, const CellEdges& edges, std::size_t first, int face, std::size_t wall,
                                int anchor_group, const LacingParams& params, double pitch_m, std::vector<bool>& taken,
                                std::vector<bool>& taken_across) {
  const std::size_t n = edges.faces.size();
  checkPlate(scene, edges, first, face, wall, "lacePlateAsNeighbour");
  if (!(pitch_m > 0.0)) throw std::invalid_argument("lacePlateAsNeighbour: the pitch must be > 0");
  taken.resize(n, false), taken_across.resize(n, false);
  const WallSpec& plate = scene.walls[wall];
  const Vec3 u = plate.axis_u, v = plate.normal.cross(u);
  const auto over = [&](const Vec3& x) {  // (over this plate's rectangle: a face in tiles, each node on one)
    const Vec3 rel = x - plate.point_m;
    return std::fabs(rel.dot(u)) <= plate.half_u_m && std::fabs(rel.dot(v)) <= plate.half_v_m;
  };
  const int axis = face % 3, facing = faceIndex(axis, face < 3 ? 1 : 0);
  Vec3 shift = Vec3::Zero();
  shift[axis] = face < 3 ? -pitch_m : pitch_m;
  // This face's edge nodes over the plate, and the neighbour's facing ones:
  // this cell's own of the facing face, one pitch over.
  std::vector<std::size_t> mine, theirs;
  std::vector<Vec3> at_mine, at_theirs;
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3& x = scene.spheres[first + k].center_m;
    if (!taken[k] && edges.onEdgeOf(k, face) && over(x)) mine.push_back(k), at_mine.push_back(x);
    if (!taken_across[k] && edges.onEdgeOf(k, facing) && over(x + shift))
      theirs.push_back(k), at_theirs.push_back(x + shift);
  }
  const bridge::WireCurve curve = wireCurveOf(params);
  LacedPlate out;
  std::vector<bool> laced(mine.size(), false);
  // (paired as laceFaces pairs them, the lower cell's face first: the
  // same wires, in the same order, as with the neighbour there)
  const bool below_neighbour = face >= 3;  // (its upper face: this cell the lower one)
  for (auto [d, i, j] :
       nearestPairs(below_neighbour ? at_mine : at_theirs, below_neighbour ? at_theirs : at_mine, params.max_gap_m)) {
    if (!below_neighbour) std::swap(i, j);
    laced[i] = true;
    taken[mine[i]] = taken_across[theirs[j]] = true;
    const SphereSpec anchor = plateAnchor(scene.spheres[first + mine[i]], at_theirs[j], wall, anchor_group);
    scene.links.push_back(lacingWire(first + mine[i], scene.spheres.size(), d, params, curve));
    scene.spheres.push_back(anchor);
    ++out.links;
  }
  for (std::size_t i = 0; i < mine.size(); ++i)
    if (!laced[i]) taken[mine[i]] = true, ++out.unlaced;
  return out;
}

LacedFaces laceFaces(const Scene& scene, const CellEdges& edges, std::size_t first_a, std::size_t first_b, int axis,
                     const LacingParams& params) {
  const std::size_t n = edges.faces.size();
  if (axis < 0 || axis > 2) throw std::invalid_argument("laceFaces: axis must be 0, 1 or 2");
  if (std::max(first_a, first_b) + n > scene.spheres.size())
    throw std::invalid_argument("laceFaces: a cell's spheres run past the scene's");
  const int fa = faceIndex(axis, 1), fb = faceIndex(axis, 0);
  std::vector<std::size_t> as, bs;
  std::vector<Vec3> at_a, at_b;
  for (std::size_t k = 0; k < n; ++k) {
    if (edges.onEdgeOf(k, fa)) as.push_back(k), at_a.push_back(scene.spheres[first_a + k].center_m);
    if (edges.onEdgeOf(k, fb)) bs.push_back(k), at_b.push_back(scene.spheres[first_b + k].center_m);
  }
  LacedFaces out;
  const bridge::WireCurve curve = wireCurveOf(params);
  for (const auto& [d, i, j] : nearestPairs(at_a, at_b, params.max_gap_m))
    out.links.push_back(lacingWire(first_a + as[i], first_b + bs[j], d, params, curve));
  out.unlaced = as.size() + bs.size() - 2 * out.links.size();
  return out;
}

}  // namespace gabion::micro
