#include "micro/netting/mesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <set>
#include <stdexcept>

#include "bridge/laws/wire_beam.hpp"

namespace gabion::micro {

const char* wireKindName(WireKind kind) {
  switch (kind) {
    case WireKind::Single:
      return "single";
    case WireKind::DoubleTwist:
      return "double_twist";
    case WireKind::Selvedge:
      return "selvedge";
    case WireKind::Lacing:
      return "lacing";
  }
  return "?";
}

namespace {

// A sheet of `columns` twists per full row and `rows` rows, in its own
// plane (z = 0), without masses: nodes, links, its first row's bottom nodes
// and its last row's top nodes.
Netting sheetLayout(const MeshSpec& mesh, int columns, int rows) {
  const double D = mesh.opening_m, a = mesh.twist_length_m, b = mesh.wire_rise_m;
  Netting net;
  net.width_m = (columns - 1) * D;
  net.length_m = rows * a + (rows - 1) * b;
  // Nodes row by row: bottom and top node of each twist.
  std::vector<std::vector<std::uint32_t>> bottom(static_cast<std::size_t>(rows)), top(bottom.size());
  std::vector<std::vector<double>> xs(bottom.size());
  for (int r = 0; r < rows; ++r) {
    const bool full = r % 2 == 0;
    const int n = full ? columns : columns - 1;
    const double y = r * (a + b);
    for (int k = 0; k < n; ++k) {
      const double x = full ? k * D : (k + 0.5) * D;
      xs[static_cast<std::size_t>(r)].push_back(x);
      bottom[static_cast<std::size_t>(r)].push_back(static_cast<std::uint32_t>(net.node_m.size()));
      net.node_m.emplace_back(x, y, 0.0);
      top[static_cast<std::size_t>(r)].push_back(static_cast<std::uint32_t>(net.node_m.size()));
      net.node_m.emplace_back(x, y + a, 0.0);
    }
  }
  const auto add = [&](std::uint32_t i, std::uint32_t j, WireKind kind) {
    net.links.push_back({i, j, kind, (net.node_m[j] - net.node_m[i]).norm()});
  };
  for (std::size_t r = 0; r < bottom.size(); ++r) {
    const bool full = r % 2 == 0;
    for (std::size_t k = 0; k < bottom[r].size(); ++k) {
      // A twist on a side edge is where the selvedge runs.
      const bool edge = full && (k == 0 || k + 1 == bottom[r].size());
      add(bottom[r][k], top[r][k], edge ? WireKind::Selvedge : WireKind::DoubleTwist);
    }
    if (r + 1 == bottom.size()) break;
    // Single wires up to the next row, at x - D/2 and x + D/2.
    for (std::size_t k = 0; k < top[r].size(); ++k) {
      const double x = xs[r][k];
      for (std::size_t q = 0; q < bottom[r + 1].size(); ++q)
        if (std::fabs(std::fabs(xs[r + 1][q] - x) - 0.5 * D) < 1e-9 * D)
          add(top[r][k], bottom[r + 1][q], WireKind::Single);
    }
    // The selvedge between the full rows r and r + 2 on both side edges.
    if (full && r + 2 < bottom.size()) {
      add(top[r].front(), bottom[r + 2].front(), WireKind::Selvedge);
      add(top[r].back(), bottom[r + 2].back(), WireKind::Selvedge);
    }
  }
  net.bottom_edge = bottom.front();
  net.top_edge = top.back();
  return net;
}

}  // namespace

// Beads: `mesh.wire_beads` extra nodes evenly along every single wire, so
// that the rock meets the wire between the twists and not only at their
// ends (docs/netting.md, `wire_beads`). Each piece is a wire of its share of the
// rest length; a bead belongs to the faces both its wire's ends are on.
void beadSingleWires(const MeshSpec& mesh, Netting& net) {
  if (mesh.wire_beads <= 0) return;
  std::vector<std::uint8_t> face_bits(net.node_m.size(), 0);
  for (std::size_t f = 0; f < net.faces.size(); ++f)
    for (const std::uint32_t k : net.faces[f]) face_bits[k] |= static_cast<std::uint8_t>(1u << f);
  const int pieces = mesh.wire_beads + 1;
  std::vector<NettingLink> links;
  for (const NettingLink& l : net.links) {
    if (l.kind != WireKind::Single) {
      links.push_back(l);
      continue;
    }
    const Vec3 a = net.node_m[l.a], b = net.node_m[l.b];
    const std::uint8_t bits = face_bits[l.a] & face_bits[l.b];
    std::uint32_t prev = l.a;
    for (int k = 1; k <= pieces; ++k) {
      std::uint32_t next = l.b;
      if (k < pieces) {
        next = static_cast<std::uint32_t>(net.node_m.size());
        net.node_m.push_back(a + (b - a) * (static_cast<double>(k) / pieces));
        for (std::size_t f = 0; f < net.faces.size(); ++f)
          if (bits & (1u << f)) net.faces[f].push_back(next);
      }
      links.push_back({prev, next, WireKind::Single, l.rest_length_m / pieces});
      prev = next;
    }
  }
  net.links = std::move(links);
}

Netting flatSheet(const MeshSpec& mesh, double width_m, double length_m) {
  const double D = mesh.opening_m, a = mesh.twist_length_m, b = mesh.wire_rise_m;
  if (!(width_m >= D) || !(length_m >= 3.0 * a + 2.0 * b))
    throw std::invalid_argument(
        "a sheet must hold at least one mesh: width >= opening and length >= 3 twists + 2 rises");
  // Whole meshes; an odd number of rows, so that both ends are full rows
  // with nodes on the side edges.
  const auto columns = static_cast<int>(std::floor(width_m / D + 1e-9)) + 1;  // twists of a full row
  auto rows = static_cast<int>(std::floor((length_m - a) / (a + b) + 1e-9)) + 1;
  if (rows % 2 == 0) --rows;
  Netting net = sheetLayout(mesh, columns, rows);
  beadSingleWires(mesh, net);
  assignNodeMasses(mesh, net);
  return net;
}

Netting closedBox(const MeshSpec& mesh, double edge_m, bool open_top) {
  const double D = mesh.opening_m, a = mesh.twist_length_m, b = mesh.wire_rise_m;
  if (!(edge_m >= D) || !(edge_m >= 2.0 * a + b))
    throw std::invalid_argument("a box edge must hold at least one mesh: edge >= opening and >= 2 twists + 1 rise");
  // Whole meshes fitted to the face: the nearest number of meshes across and
  // of rows along, the face's sheet then stretched or shrunk to the edge.
  const int meshes = std::max(1, static_cast<int>(std::lround(edge_m / D)));
  int rows = 2;
  for (int n = 3; n < 100000; ++n) {
    const double len = n * a + (n - 1) * b;
    if (std::fabs(len - edge_m) < std::fabs(rows * a + (rows - 1) * b - edge_m)) rows = n;
    if (len > edge_m) break;
  }
  const Netting face = sheetLayout(mesh, meshes + 1, rows);
  const double sx = edge_m / face.width_m, sy = edge_m / face.length_m;
  // The faces: origin and the directions of the sheet's x and y (twists along y).
  const Vec3 X = Vec3::UnitX(), Y = Vec3::UnitY(), Z = Vec3::UnitZ(), O = Vec3::Zero();
  const std::array<std::array<Vec3, 3>, 6> frames = {
      {{O, X, Y}, {edge_m * Z, X, Y}, {O, X, Z}, {edge_m * Y, X, Z}, {O, Y, Z}, {edge_m * X, Y, Z}}};
  Netting net;
  net.width_m = net.length_m = edge_m;
  std::vector<std::uint32_t> face_of;  // face of each node before merging
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (open_top && f == 1) continue;  // a basket: no lid
    const auto first = static_cast<std::uint32_t>(net.node_m.size());
    for (const Vec3& p : face.node_m) {
      net.node_m.push_back(frames[f][0] + frames[f][1] * (p.x() * sx) + frames[f][2] * (p.y() * sy));
      face_of.push_back(static_cast<std::uint32_t>(f));
    }
    for (NettingLink l : face.links) {
      l.a += first, l.b += first;
      net.links.push_back(l);
    }
  }
  // Nodes on the box's edges: where two faces meet, a node of one within two
  // node radii of a node of the other becomes that node (a shared node);
  // every other edge node is laced to the nearest edge node of the other face.
  const double r = mesh.nodeRadius(), tol = 1e-9 * edge_m;
  std::vector<std::uint32_t> same(net.node_m.size());
  for (std::size_t k = 0; k < same.size(); ++k) same[k] = static_cast<std::uint32_t>(k);
  const auto root = [&](std::uint32_t k) {
    while (same[k] != k) k = same[k];
    return k;
  };
  std::vector<std::pair<std::uint32_t, std::uint32_t>> lacing;
  for (int axis = 0; axis < 3; ++axis)
    for (const double u : {0.0, edge_m})
      for (const double v : {0.0, edge_m}) {
        // The box edge parallel to `axis` at the other two coordinates (u, v).
        const int c1 = (axis + 1) % 3, c2 = (axis + 2) % 3;
        std::vector<std::vector<std::uint32_t>> by_face(frames.size());
        for (std::uint32_t k = 0; k < net.node_m.size(); ++k) {
          const Vec3& p = net.node_m[k];
          if (std::fabs(p[c1] - u) <= tol && std::fabs(p[c2] - v) <= tol) by_face[face_of[k]].push_back(k);
        }
        // The two faces whose planes meet there (a third face's corner
        // node on the line is joined along that face's own edges).
        const auto planeFace = [&](int c, double at) {
          static constexpr std::array<std::size_t, 3> low = {4, 2, 0}, high = {5, 3, 1};
          return at == 0.0 ? low[static_cast<std::size_t>(c)] : high[static_cast<std::size_t>(c)];
        };
        const std::array<std::size_t, 2> faces = {planeFace(c1, u), planeFace(c2, v)};
        if (open_top && (faces[0] == 1 || faces[1] == 1)) continue;  // the rim of a basket
        if (by_face[faces[0]].empty() || by_face[faces[1]].empty())
          throw std::logic_error("closedBox: a face has no node on one of its edges");
        const auto& A = by_face[faces[0]];
        const auto& B = by_face[faces[1]];
        const auto nearest = [&](std::uint32_t k, const std::vector<std::uint32_t>& other) {
          std::uint32_t best = other[0];
          for (const std::uint32_t q : other)
            if ((net.node_m[q] - net.node_m[k]).norm() < (net.node_m[best] - net.node_m[k]).norm()) best = q;
          return best;
        };
        for (const std::uint32_t k : B) {
          const std::uint32_t q = nearest(k, A);
          if ((net.node_m[q] - net.node_m[k]).norm() < 2.0 * r) same[root(k)] = root(q);
        }
        for (const auto& [from, to] : {std::pair{&A, &B}, std::pair{&B, &A}})
          for (const std::uint32_t k : *from) {
            const std::uint32_t q = nearest(k, *to);
            if (root(q) != root(k)) lacing.emplace_back(k, q);
          }
      }
  // Renumber the merged nodes, re-point the links, lace, drop repeats.
  std::vector<std::uint32_t> index(net.node_m.size(), UINT32_MAX);
  std::vector<Vec3> nodes;
  for (std::uint32_t k = 0; k < net.node_m.size(); ++k)
    if (root(k) == k) index[k] = static_cast<std::uint32_t>(nodes.size()), nodes.push_back(net.node_m[k]);
  std::vector<NettingLink> links;
  std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
  const auto keep = [&](std::uint32_t i, std::uint32_t j, WireKind kind) {
    i = index[root(i)], j = index[root(j)];
    if (i == j || !seen.insert({std::min(i, j), std::max(i, j)}).second) return;
    links.push_back({i, j, kind, (nodes[j] - nodes[i]).norm()});
  };
  for (const NettingLink& l : net.links) keep(l.a, l.b, l.kind);
  for (const auto& [i, j] : lacing) keep(i, j, WireKind::Lacing);
  net.faces.assign(frames.size(), {});
  for (std::uint32_t k = 0; k < face_of.size(); ++k) {
    auto& f = net.faces[face_of[k]];
    const std::uint32_t n = index[root(k)];
    if (std::find(f.begin(), f.end(), n) == f.end()) f.push_back(n);
  }
  net.node_m = std::move(nodes);
  net.links = std::move(links);
  beadSingleWires(mesh, net);
  assignNodeMasses(mesh, net);
  return net;
}

void assignNodeMasses(const MeshSpec& mesh, Netting& net) {
  net.node_radius_m = mesh.nodeRadius();
  // The wire each node carries: half of each of its links (two wires in a
  // twist), a rod of length L / 2 turning about the node: (m / 2) (L / 2)^2 / 3.
  // With bending wires, a node's turn against its beams' end stiffness
  // (4 E I / L each) must not be faster than its sway against their shear
  // stiffness (12 E I / L^3): the lumped wire's own rotary inertia, of order
  // m L^2 / 24, would set a step (L / 2.8)^2 times shorter for every node,
  // and shorter still for the beads of short wires. Its rotary inertia is
  // raised to m sum(4 E I / L) / sum(12 E I / L^3), about m L^2 / 3, as
  // explicit beam codes scale theirs: the turn of a node is then no faster
  // than its sway, the statics are unchanged.
  const std::size_t nn = net.node_m.size();
  std::vector<double> wire(nn, 0.0), turn(nn, 0.0), k_turn(nn, 0.0), k_sway(nn, 0.0);
  for (const NettingLink& l : net.links) {
    double d = mesh.wire_diameter_m, wires = 1.0;
    if (l.kind == WireKind::Selvedge) d = mesh.selvedge_diameter_m;
    if (l.kind == WireKind::Lacing) d = mesh.lacing_diameter_m;
    if (l.kind == WireKind::DoubleTwist) wires = 2.0;
    const double half = 0.5 * wires * mesh.steel_density_kg_m3 * bridge::wireSection(d) * l.rest_length_m;
    const double I = half * 0.25 * l.rest_length_m * l.rest_length_m / 3.0;
    wire[l.a] += half, wire[l.b] += half, turn[l.a] += I, turn[l.b] += I;
    if (mesh.bending && l.kind != WireKind::Lacing) {
      const bridge::WireBeamParams b = bridge::wireBeam(1.0, 1.0, d, l.rest_length_m, wires);  // (E = 1: ratios)
      k_turn[l.a] += b.endStiffness(), k_turn[l.b] += b.endStiffness();
      k_sway[l.a] += b.shear_N_m, k_sway[l.b] += b.shear_N_m;
    }
  }
  net.node_mass_kg.assign(nn, 0.0);
  net.node_inertia_kg_m2.assign(nn, 0.0);
  for (std::size_t k = 0; k < nn; ++k) {
    const double m = mesh.node_mass_kg > 0.0 ? mesh.node_mass_kg : wire[k];
    net.node_mass_kg[k] = m;
    // (a node of no wire keeps the solid sphere's inertia)
    double I = wire[k] > 0.0 ? turn[k] * (m / wire[k]) : 0.0;
    if (k_sway[k] > 0.0) I = std::max(I, m * k_turn[k] / k_sway[k]);
    net.node_inertia_kg_m2[k] = I;
  }
}

LinkSpec linkSpec(const MeshSpec& mesh, const NettingLink& link, std::size_t first_sphere) {
  LinkSpec s;
  s.a = first_sphere + link.a;
  s.b = first_sphere + link.b;
  s.law = LinkSpec::Law::Wire;
  s.wire.rest_length_m = link.rest_length_m;
  switch (link.kind) {
    case WireKind::Single:
      s.wire.curve = bridge::wireCurve(mesh.table, mesh.wire_diameter_m);
      break;
    case WireKind::DoubleTwist:
      s.wire.curve = bridge::doubleTwistCurve(mesh.table, mesh.wire_diameter_m, mesh.twist);
      break;
    case WireKind::Selvedge:
      s.wire.curve = bridge::wireCurve(mesh.table, mesh.selvedge_diameter_m);
      break;
    case WireKind::Lacing:
      s.wire.curve = bridge::wireCurve(mesh.table, mesh.lacing_diameter_m);
      break;
  }
  if (mesh.bending && link.kind != WireKind::Lacing) {
    // The table's first point: the elastic modulus and the yield stress.
    const double yield = mesh.table.stress_Pa.front(), E = yield / mesh.table.strain.front();
    const double d = link.kind == WireKind::Selvedge ? mesh.selvedge_diameter_m : mesh.wire_diameter_m;
    s.beam = bridge::wireBeam(E, yield, d, link.rest_length_m, link.kind == WireKind::DoubleTwist ? 2.0 : 1.0);
  }
  return s;
}

}  // namespace gabion::micro
