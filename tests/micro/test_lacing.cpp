// Lacing between neighbouring cells (micro/netting/lacing.hpp): the faces of
// a cell's netting found from its nodes alone, and the lacing wires between
// the facing edges of two cells.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "micro/lab/structure_impact.hpp"
#include "micro/netting/lacing.hpp"
#include "micro/netting/mesh.hpp"

namespace {

using gabion::micro::CellEdges;
using gabion::micro::cellEdges;
using gabion::micro::faceIndex;
using gabion::micro::laceFaces;
using gabion::micro::lacePlateAsNeighbour;
using gabion::micro::LacingParams;
using gabion::micro::LinkSpec;
using gabion::micro::Scene;
using gabion::micro::SphereSpec;
using gabion::micro::Vec3;
using gabion::micro::WallSpec;

constexpr double kEdge = 0.5;

// A closed box of the default mesh as a cell: its nodes (spheres) and wires.
Scene boxCell() {
  const gabion::micro::MeshSpec mesh;
  const gabion::micro::Netting box = gabion::micro::closedBox(mesh, kEdge);
  Scene s;
  for (const Vec3& x : box.node_m) {
    SphereSpec sp;
    sp.center_m = x;
    sp.radius_m = box.node_radius_m;
    s.spheres.push_back(sp);
  }
  for (const auto& l : box.links) s.links.push_back(gabion::micro::linkSpec(mesh, l, 0));
  return s;
}

// Whether x lies within `band` of a plane across axis `axis` of the cube
// [0, kEdge]^3 (of either end of either other axis).
bool nearAnEdgeAcross(const Vec3& x, int axis, double band) {
  for (int b = 0; b < 3; ++b)
    if (b != axis && (std::fabs(x[b]) <= band || std::fabs(x[b] - kEdge) <= band)) return true;
  return false;
}

// On a flat box the faces' planes are the cube's, and a face's edge nodes
// are its nodes near the faces across it. With the lid pushed up in its
// middle (a filled cell's upright block), the lid's plane stays where most
// of the lid is: the nodes' extent would put it 80 mm too high, and find
// none of the lid's edges.
TEST(Lacing, FindsTheFacesOfACellsNettingFromItsNodes) {
  Scene cell = boxCell();
  const double band = 0.016;
  const CellEdges flat = cellEdges(cell, band);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(flat.plane[faceIndex(a, 0)], 0.0, 1e-12) << "axis " << a;
    EXPECT_NEAR(flat.plane[faceIndex(a, 1)], kEdge, 1e-12) << "axis " << a;
  }
  for (int f = 0; f < 6; ++f) {
    std::size_t edge = 0;
    for (std::size_t k = 0; k < cell.spheres.size(); ++k) {
      const Vec3& x = cell.spheres[k].center_m;
      const bool on = std::fabs(x[f % 3] - (f < 3 ? 0.0 : kEdge)) <= band && nearAnEdgeAcross(x, f % 3, band);
      EXPECT_EQ(flat.onEdgeOf(k, f), on) << "face " << f << " node " << k;
      edge += on ? 1 : 0;
    }
    EXPECT_GE(edge, 4u * 5u) << "face " << f << ": at least five nodes along each of its four edges";
  }

  // The lid's middle pushed up (inside a 0.3 m square), up to 80 mm.
  std::set<std::size_t> lid_edge;
  for (std::size_t k = 0; k < cell.spheres.size(); ++k) {
    Vec3& x = cell.spheres[k].center_m;
    if (flat.onEdgeOf(k, faceIndex(2, 1))) lid_edge.insert(k);
    const double u = std::fabs(x.x() - 0.5 * kEdge), v = std::fabs(x.y() - 0.5 * kEdge);
    if (std::fabs(x.z() - kEdge) < 1e-9 && u < 0.15 && v < 0.15) x.z() += 0.08 * (1.0 - std::max(u, v) / 0.15);
  }
  const CellEdges lifted = cellEdges(cell, band);
  EXPECT_NEAR(lifted.plane[faceIndex(2, 1)], kEdge, 1e-12);
  std::set<std::size_t> found;
  for (std::size_t k = 0; k < cell.spheres.size(); ++k)
    if (lifted.onEdgeOf(k, faceIndex(2, 1))) found.insert(k);
  EXPECT_EQ(found, lid_edge);
  EXPECT_THROW(cellEdges(cell, 0.0), std::invalid_argument);
}

// A cell's lid lies under its extent by the lift of its highest node
// (micro::lab::lidClearance, where a hybrid's plates under its resolved
// cells stand with resolve.below "lid"): 0 on a flat box; with the lid's
// middle pushed up (up to 80 mm), that node's lift (the lid's plane stays
// where most of the lid is); 0 without a netting.
TEST(Lacing, ALidLiesUnderTheCellsExtentByItsHighestNodesLift) {
  gabion::micro::lab::Sample sample;
  sample.scene = boxCell();
  const auto extent = [&] {
    sample.lo = Vec3::Constant(1e9), sample.hi = Vec3::Constant(-1e9);
    for (const SphereSpec& s : sample.scene.spheres) {
      sample.lo = sample.lo.cwiseMin(s.center_m - Vec3::Constant(s.radius_m));
      sample.hi = sample.hi.cwiseMax(s.center_m + Vec3::Constant(s.radius_m));
    }
  };
  extent();
  EXPECT_NEAR(gabion::micro::lab::lidClearance(sample), 0.0, 1e-12);
  double lift = 0.0;  // (the highest node's)
  for (SphereSpec& s : sample.scene.spheres) {
    Vec3& x = s.center_m;
    const double u = std::fabs(x.x() - 0.5 * kEdge), v = std::fabs(x.y() - 0.5 * kEdge);
    if (std::fabs(x.z() - kEdge) < 1e-9 && u < 0.15 && v < 0.15) {
      const double up = 0.08 * (1.0 - std::max(u, v) / 0.15);
      x.z() += up, lift = std::max(lift, up);
    }
  }
  extent();
  EXPECT_GT(lift, 0.07);
  EXPECT_NEAR(gabion::micro::lab::lidClearance(sample), lift, 1e-12);
  sample.scene.links.clear();
  EXPECT_EQ(gabion::micro::lab::lidClearance(sample), 0.0);
}

// Two boxes side by side along each axis, `gap` apart: every lacing wire
// joins an edge node of the first's upper face to one of the second's
// lower face, each node at most once, stress free at the distance they
// are laced at (at least min_length_m), none longer than max_gap_m; nearly
// every edge node is laced; the same scene gives the same links; beyond
// reach, none.
TEST(Lacing, LacesTheFacingEdgesOfTwoCellsNodeToNode) {
  const Scene cell = boxCell();
  const std::size_t n = cell.spheres.size();
  const double gap = 0.03, band = 0.016;
  const CellEdges edges = cellEdges(cell, band);
  for (int axis = 0; axis < 3; ++axis) {
    Scene two = cell;
    for (const SphereSpec& s : cell.spheres) {
      SphereSpec t = s;
      t.center_m[axis] += kEdge + gap;
      two.spheres.push_back(t);
    }
    LacingParams p;
    p.max_gap_m = 0.06;
    p.min_length_m = 0.035;
    const auto laced = laceFaces(two, edges, 0, n, axis, p);
    std::size_t on_a = 0, on_b = 0;
    for (std::size_t k = 0; k < n; ++k)
      on_a += edges.onEdgeOf(k, faceIndex(axis, 1)) ? 1 : 0, on_b += edges.onEdgeOf(k, faceIndex(axis, 0)) ? 1 : 0;
    std::set<std::size_t> used;
    for (const LinkSpec& l : laced.links) {
      ASSERT_LT(l.a, n);
      ASSERT_GE(l.b, n);
      EXPECT_TRUE(edges.onEdgeOf(l.a, faceIndex(axis, 1)));
      EXPECT_TRUE(edges.onEdgeOf(l.b - n, faceIndex(axis, 0)));
      EXPECT_TRUE(used.insert(l.a).second && used.insert(l.b).second) << "a node laced twice";
      const double d = (two.spheres[l.b].center_m - two.spheres[l.a].center_m).norm();
      EXPECT_LE(d, p.max_gap_m);
      EXPECT_GE(d, gap - 1e-12);
      EXPECT_EQ(l.wire.rest_length_m, std::max(d, p.min_length_m));
      EXPECT_EQ(l.law, LinkSpec::Law::Wire);
      // (the lacing wire: 2.2 mm of the default steel, 250 MPa at its first point)
      EXPECT_NEAR(l.wire.curve.force().front(), 250e6 * M_PI * 0.0011 * 0.0011, 1e-6);
    }
    EXPECT_EQ(laced.links.size() * 2 + laced.unlaced, on_a + on_b);
    EXPECT_GE(laced.links.size(), (8 * std::min(on_a, on_b)) / 10) << "axis " << axis;
    const auto again = laceFaces(two, edges, 0, n, axis, p);
    ASSERT_EQ(again.links.size(), laced.links.size());
    for (std::size_t k = 0; k < laced.links.size(); ++k)
      EXPECT_TRUE(again.links[k].a == laced.links[k].a && again.links[k].b == laced.links[k].b);
    p.max_gap_m = 0.5 * gap;
    const auto none = laceFaces(two, edges, 0, n, axis, p);
    EXPECT_TRUE(none.links.empty());
    EXPECT_EQ(none.unlaced, on_a + on_b);
  }
}

// A face laced to a plate as to a neighbouring copy of the cell
// (lacePlateAsNeighbour) gets the wires laceFaces gives it with that copy
// there, one pitch over: the same number, each from the same node, to an
// anchor where the copy's partner node stands, at the same length, on the
// upper face and on the lower; the anchors ride the plate and touch
// nothing. A face cut in two tiles gets them once, split between the
// tiles.
TEST(Lacing, AFaceLacedToAPlateAsToItsNeighbourGetsTheNeighboursWires) {
  const Scene cell = boxCell();
  const std::size_t n = cell.spheres.size();
  const double gap = 0.03, pitch = kEdge + gap;
  const CellEdges edges = cellEdges(cell, 0.016);
  LacingParams p;
  p.max_gap_m = 0.06;
  p.min_length_m = 0.035;
  for (int axis = 0; axis < 3; ++axis)
    for (int upper = 0; upper < 2; ++upper) {
      // The copy beside it, for laceFaces (the lower cell first).
      Scene two = cell;
      for (const SphereSpec& s : cell.spheres) {
        SphereSpec t = s;
        t.center_m[axis] += upper ? pitch : -pitch;
        two.spheres.push_back(t);
      }
      const std::size_t lower = upper ? 0 : n, higher = upper ? n : 0;
      const auto pair = laceFaces(two, edges, lower, higher, axis, p);
      ASSERT_GT(pair.links.size(), 20u);
      // The plate on that face, its normal into the cell, over the whole face.
      const auto plateScene = [&](int tiles) {
        Scene one = cell;
        for (int t = 0; t < tiles; ++t) {
          WallSpec w;
          w.bounded = true;
          w.normal = Vec3::Zero(), w.normal[axis] = upper ? -1.0 : 1.0;
          w.axis_u = Vec3::Zero(), w.axis_u[(axis + 1) % 3] = 1.0;
          w.point_m = Vec3::Constant(0.5 * kEdge), w.point_m[axis] = upper ? kEdge : 0.0;
          w.half_u_m = 0.5 * kEdge / tiles + 0.05, w.half_v_m = 0.5 * kEdge + 0.05;
          w.point_m[(axis + 1) % 3] += (t - 0.5 * (tiles - 1)) * kEdge / tiles;
          one.walls.push_back(w);
        }
        return one;
      };
      Scene one = plateScene(1);
      std::vector<bool> taken, taken_across;
      const int face = faceIndex(axis, upper);
      const auto laced = lacePlateAsNeighbour(one, edges, 0, face, 0, 3, p, pitch, taken, taken_across);
      ASSERT_EQ(laced.links, pair.links.size()) << "axis " << axis << (upper ? " upper" : " lower");
      ASSERT_EQ(one.links.size(), cell.links.size() + laced.links);
      ASSERT_EQ(one.spheres.size(), n + laced.links);
      std::size_t on_face = 0;
      for (std::size_t k = 0; k < n; ++k) on_face += edges.onEdgeOf(k, face) ? 1 : 0;
      EXPECT_EQ(laced.links + laced.unlaced, on_face);
      for (std::size_t k = 0; k < laced.links; ++k) {
        const LinkSpec& mine = one.links[cell.links.size() + k];
        const LinkSpec& theirs = pair.links[k];
        // (laceFaces' a is the lower cell's node: this cell's on its upper face)
        const std::size_t node = upper ? theirs.a : theirs.b, partner = upper ? theirs.b : theirs.a;
        EXPECT_EQ(mine.a, node);
        ASSERT_EQ(mine.b, n + k);
        const SphereSpec& anchor = one.spheres[mine.b];
        EXPECT_LT((anchor.center_m - two.spheres[partner].center_m).norm(), 1e-12);
        EXPECT_EQ(mine.wire.rest_length_m, theirs.wire.rest_length_m);
        EXPECT_TRUE(anchor.fixed);
        EXPECT_EQ(anchor.rides_wall, 0);
        EXPECT_EQ(anchor.group, 3);
      }
      // In two tiles: every node once, the same wires between them.
      Scene tiled = plateScene(2);
      std::vector<bool> t2, a2;
      const auto first = lacePlateAsNeighbour(tiled, edges, 0, face, 0, 3, p, pitch, t2, a2);
      const auto second = lacePlateAsNeighbour(tiled, edges, 0, face, 1, 3, p, pitch, t2, a2);
      EXPECT_GT(first.links, 0u);
      EXPECT_GT(second.links, 0u);
      EXPECT_NEAR(static_cast<double>(first.links + second.links), static_cast<double>(laced.links), 0.1 * laced.links);
      std::set<std::size_t> used;
      for (std::size_t k = cell.links.size(); k < tiled.links.size(); ++k)
        EXPECT_TRUE(used.insert(tiled.links[k].a).second) << "a node laced twice";
    }
}

}  // namespace
