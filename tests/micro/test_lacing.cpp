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
using gabion::micro::LacingParams;
using gabion::micro::LinkSpec;
using gabion::micro::Scene;
using gabion::micro::SphereSpec;
using gabion::micro::Vec3;

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

}  // namespace
