#include "micro/netting/mesh.hpp"

#include <cmath>
#include <stdexcept>

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
  assignNodeMasses(mesh, net);
  return net;
}

void assignNodeMasses(const MeshSpec& mesh, Netting& net) {
  net.node_radius_m = mesh.nodeRadius();
  net.node_mass_kg.assign(net.node_m.size(), mesh.node_mass_kg);
  if (mesh.node_mass_kg <= 0.0) {
    // The wire each node carries: half of each of its links (two wires in a twist).
    for (const NettingLink& l : net.links) {
      double d = mesh.wire_diameter_m, wires = 1.0;
      if (l.kind == WireKind::Selvedge) d = mesh.selvedge_diameter_m;
      if (l.kind == WireKind::Lacing) d = mesh.lacing_diameter_m;
      if (l.kind == WireKind::DoubleTwist) wires = 2.0;
      const double half = 0.5 * wires * mesh.steel_density_kg_m3 * bridge::wireSection(d) * l.rest_length_m;
      net.node_mass_kg[l.a] += half;
      net.node_mass_kg[l.b] += half;
    }
  }
  for (double& m : net.node_mass_kg) m *= mesh.node_mass_scale;
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
  return s;
}

}  // namespace gabion::micro
