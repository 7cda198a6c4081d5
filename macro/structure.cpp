#include "macro/structure.hpp"

#include <cmath>
#include <map>
#include <stdexcept>

namespace gabion::macro {

using bridge::AxialLawParams;
using bridge::AxialModel;

AxialLawParams seriesAxialLaw(const AxialLawParams& a, const AxialLawParams& b) {
  auto series = [](double x, double y) { return x + y > 0.0 ? 2.0 * x * y / (x + y) : 0.0; };
  AxialLawParams p;
  p.stiffness_N_m = series(a.stiffness_N_m, b.stiffness_N_m);
  p.yield_force_N = std::min(a.yield_force_N, b.yield_force_N);
  if (bridge::hardens(a.model) && bridge::hardens(b.model)) {
    p.model = a.model == b.model ? a.model : AxialModel::Bilinear;
    p.hardening_stiffness_N_m = series(a.hardening_stiffness_N_m, b.hardening_stiffness_N_m);
  }
  // Each half cell densifies and locks up at half its cell's shortenings.
  if (a.model == AxialModel::Densifying && b.model == AxialModel::Densifying) {
    p.densification_onset_m = 0.5 * (a.densification_onset_m + b.densification_onset_m);
    p.densification_stiffness_N_m = series(a.densification_stiffness_N_m, b.densification_stiffness_N_m);
    p.plastic_densification = a.plastic_densification && b.plastic_densification;
    // (a stiffness: in series; kept only where both halves have one)
    const double ra = a.densification_unloading_stiffness_N_m, rb = b.densification_unloading_stiffness_N_m;
    p.densification_unloading_stiffness_N_m = p.plastic_densification && ra > 0.0 && rb > 0.0 ? series(ra, rb) : 0.0;
  }
  p.lockup_shortening_m = 0.5 * (a.lockup_shortening_m + b.lockup_shortening_m);
  p.lockup_stiffness_N_m = series(a.lockup_stiffness_N_m, b.lockup_stiffness_N_m);
  p.viscosity_N_s_m = series(a.viscosity_N_s_m, b.viscosity_N_s_m);  // (two dashpots in series, as the springs)
  // The momentum flux c_m r^2 of two half cells in series: each half (4 c_m,
  // cellLengthLaw) takes the part of the rate that gives both the same
  // force, so 1 / sqrt(c_m) adds up: c_m = 4 / (1/sqrt(c_a) + 1/sqrt(c_b))^2,
  // c_m itself for two equal cells, 0 when either half has none; its growth
  // a shortening, as the densification onset.
  const double ca = a.momentum_flux_kg_m, cb = b.momentum_flux_kg_m;
  p.momentum_flux_kg_m = ca > 0.0 && cb > 0.0 ? 4.0 / std::pow(1.0 / std::sqrt(ca) + 1.0 / std::sqrt(cb), 2) : 0.0;
  p.momentum_flux_growth_m = 0.5 * (a.momentum_flux_growth_m + b.momentum_flux_growth_m);
  return p;
}

AxialLawParams cellLengthLaw(const AxialLawParams& a, double factor) {
  AxialLawParams p = a;
  p.stiffness_N_m /= factor;
  p.hardening_stiffness_N_m /= factor;
  p.densification_onset_m *= factor;
  p.densification_stiffness_N_m /= factor;
  p.softening_stiffness_N_m /= factor;
  p.softening_onset_m *= factor;
  p.lockup_shortening_m *= factor;
  p.lockup_stiffness_N_m /= factor;
  p.densification_unloading_stiffness_N_m /= factor;
  p.viscosity_N_s_m /= factor;              // (a viscosity per strain rate, as a stiffness per strain)
  p.momentum_flux_kg_m /= factor * factor;  // (a force that goes with the strain rate squared: c_m L^2)
  p.momentum_flux_growth_m *= factor;
  return p;
}

AxialLawParams halfCellLaw(const AxialLawParams& a) {
  return cellLengthLaw(a, 0.5);
}

double crushShortening(const AxialLawParams& p, double length_m) {
  if (!std::isfinite(p.lockup_shortening_m)) return INFINITY;
  return p.lockup_shortening_m + kCrushFraction * (length_m - p.lockup_shortening_m);
}

int Structure::nodeAt(int i, int j, int k) const {
  if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) return -1;
  return node_of[static_cast<std::size_t>(i + nx * (j + ny * k))];
}

namespace {

// Deduplicating tables of laws: equal parameters (and lengths) share one entry.
// `length_m`: what the law spans (a cell edge; half of one against a support).
int internAxial(Structure& s, const AxialLawParams& p, double length_m) {
  const double crush = crushShortening(p, length_m);
  for (std::size_t i = 0; i < s.axial_laws.size(); ++i) {
    if (bridge::sameLaw(s.axial_laws[i], p) && s.axial_crush_m[i] == crush) return static_cast<int>(i);
  }
  s.axial_laws.push_back(p);
  s.axial_springs.push_back(bridge::cellSpring(p));
  s.axial_crush_m.push_back(crush);
  return static_cast<int>(s.axial_laws.size() - 1);
}

int internFriction(Structure& s, const bridge::FrictionParams& p) {
  for (std::size_t i = 0; i < s.friction_laws.size(); ++i)
    if (s.friction_laws[i].friction == p.friction &&
        s.friction_laws[i].tangential_stiffness_N_m == p.tangential_stiffness_N_m)
      return static_cast<int>(i);
  s.friction_laws.push_back(p);
  s.friction_half_inv_k.push_back(0.5 / p.tangential_stiffness_N_m);
  return static_cast<int>(s.friction_laws.size() - 1);
}

// The interface of two materials: the smaller friction, tangential springs in series.
bridge::FrictionParams pairFriction(const bridge::CellMaterial& a, const bridge::CellMaterial& b) {
  const double ka = a.interface.tangential_stiffness_N_m, kb = b.interface.tangential_stiffness_N_m;
  return {std::min(a.interface.friction, b.interface.friction), 2.0 * ka * kb / (ka + kb)};
}

}  // namespace

Structure buildStructure(const StructureSpec& spec, const bridge::LawFile& laws) {
  if (spec.nx < 1 || spec.ny < 1 || spec.nz < 1) throw std::invalid_argument("cell counts must be >= 1");
  Structure s;
  s.nx = spec.nx;
  s.ny = spec.ny;
  s.nz = spec.nz;
  s.front_offset_cells = spec.front_offset_cells.empty() ? std::vector<int>(static_cast<std::size_t>(spec.nz), 0)
                                                         : spec.front_offset_cells;
  if (static_cast<int>(s.front_offset_cells.size()) != spec.nz)
    throw std::invalid_argument("front_offset_cells needs one entry per z layer (" + std::to_string(spec.nz) + ")");
  for (int off : s.front_offset_cells)
    if (off < 0 || off >= spec.nx)
      throw std::invalid_argument("front_offset_cells entries must be in [0, " + std::to_string(spec.nx - 1) + "]");

  // Materials: index by name, in the order of first use.
  std::map<std::string, int> index;
  auto materialIndex = [&](const std::string& name) {
    std::string n = name;
    if (n.empty()) {
      if (laws.materials.size() != 1)
        throw std::invalid_argument("the law file has several materials: name the cells' materials");
      n = laws.materials.begin()->first;
    }
    auto it = index.find(n);
    if (it != index.end()) return it->second;
    auto m = laws.materials.find(n);
    if (m == laws.materials.end()) throw std::invalid_argument("material '" + n + "' is not in the law file");
    const int id = static_cast<int>(s.materials.size());
    s.materials.push_back(m->second);
    s.material_names.push_back(n);
    index.emplace(n, id);
    return id;
  };

  // Nodes.
  s.node_of.assign(static_cast<std::size_t>(s.nx) * s.ny * s.nz, -1);
  std::vector<char> resolved(s.node_of.size(), 0);
  for (const int c : spec.resolved_cells) {
    if (c < 0 || static_cast<std::size_t>(c) >= resolved.size())
      throw std::invalid_argument("resolved cell index " + std::to_string(c) + " is outside the grid");
    resolved[static_cast<std::size_t>(c)] = 1;
  }
  const auto isResolved = [&](int i, int j, int k) {
    return i >= 0 && j >= 0 && k >= 0 && i < s.nx && j < s.ny && k < s.nz &&
           resolved[static_cast<std::size_t>(i + s.nx * (j + s.ny * k))] != 0;
  };
  std::size_t explicit_next = 0;
  // Every cell's material, resolved or not (-1: none, a stepped front).
  std::vector<int> cell_material(static_cast<std::size_t>(s.nx) * s.ny * s.nz, -1);
  for (int k = 0; k < s.nz; ++k)
    for (int j = 0; j < s.ny; ++j)
      for (int i = s.front_offset_cells[static_cast<std::size_t>(k)]; i < s.nx; ++i) {
        std::string name;
        if (!spec.material.cells.empty()) {
          if (explicit_next >= spec.material.cells.size())
            throw std::invalid_argument("the material list is shorter than the number of cells");
          name = spec.material.cells[explicit_next++];
        } else {
          const int depth = i - s.front_offset_cells[static_cast<std::size_t>(k)];
          name = depth < spec.material.front_depth_cells ? spec.material.front : spec.material.core;
        }
        cell_material[static_cast<std::size_t>(i + s.nx * (j + s.ny * k))] = materialIndex(name);
        if (isResolved(i, j, k)) {
          // (behind a macro cell of the front layer, whose front face is
          // free: that node meets it at its rear face, below; behind a
          // macro cell with another in front, the link between those two
          // would span one and a half cells)
          const int front = s.front_offset_cells[static_cast<std::size_t>(k)];
          if (i > front + 1 && !isResolved(i - 1, j, k))
            throw std::invalid_argument("resolved cell (" + std::to_string(i) + ", " + std::to_string(j) + ", " +
                                        std::to_string(k) +
                                        ") is behind a macro cell that is not in the front layer: resolve the cells "
                                        "in front too, or only those of the front layer");
          continue;
        }
        const int node = static_cast<int>(s.gi.size());
        s.node_of[static_cast<std::size_t>(i + s.nx * (j + s.ny * k))] = node;
        s.gi.push_back(i);
        s.gj.push_back(j);
        s.gk.push_back(k);
        s.material.push_back(materialIndex(name));
      }
  if (!spec.material.cells.empty() && explicit_next != spec.material.cells.size())
    throw std::invalid_argument("the material list has " + std::to_string(spec.material.cells.size()) + " names for " +
                                std::to_string(explicit_next) + " cells");

  s.edge_m = s.materials.front().edge_m;
  for (std::size_t m = 0; m < s.materials.size(); ++m)
    if (std::abs(s.materials[m].edge_m - s.edge_m) > 1e-12 * s.edge_m)
      throw std::invalid_argument("material '" + s.material_names[m] + "' has edge_m " +
                                  std::to_string(s.materials[m].edge_m) + " but '" + s.material_names[0] + "' has " +
                                  std::to_string(s.edge_m) + ": the grid needs one cell size");
  const double e = s.edge_m;
  const std::size_t n = s.gi.size();
  for (std::size_t q = 0; q < n; ++q) {
    const auto& mat = s.materials[static_cast<std::size_t>(s.material[q])];
    s.x0.push_back((s.gi[q] + 0.5) * e);
    s.y0.push_back((s.gj[q] + 0.5) * e);
    s.z0.push_back((s.gk[q] + 0.5) * e);
    s.mass_kg.push_back(mat.mass_kg);
    s.inv_mass.push_back(1.0 / mat.mass_kg);
    s.reaction_coefficient.push_back(mat.lateral.reaction_coefficient);
  }

  // Interactions.
  for (std::size_t q = 0; q < n; ++q) {
    const int i = s.gi[q], j = s.gj[q], k = s.gk[q];
    const auto& ma = s.materials[static_cast<std::size_t>(s.material[q])];
    const int a = static_cast<int>(q);
    // (a node behind a resolved cell meets it at its front face: its rear
    // link spans the whole of its cell)
    const bool whole = isResolved(i - 1, j, k);
    const AxialLawParams rear = whole ? cellLengthLaw(ma.axial, 2.0) : ma.axial;
    if (isResolved(i + 1, j, k)) {
      // A front node with a resolved cell behind it meets that cell at its
      // rear face: no link behind it, the plate on the resolved cell's
      // front face moves with it (its cell a rigid mass along x between
      // its free front face and that plate).
    } else if (const int b = s.nodeAt(i + 1, j, k); b >= 0) {
      const auto& mb = s.materials[static_cast<std::size_t>(s.material[static_cast<std::size_t>(b)])];
      s.axial.a.push_back(a);
      s.axial.b.push_back(b);
      s.axial.law.push_back(internAxial(s, seriesAxialLaw(rear, mb.axial), whole ? 1.5 * e : e));
      s.axial.friction.push_back(internFriction(s, pairFriction(ma, mb)));
    } else {
      s.back_nodes.push_back(a);
      if (spec.support.fixed_back) {
        s.axial.a.push_back(a);
        s.axial.b.push_back(kWall);
        s.axial.law.push_back(internAxial(s, halfCellLaw(rear), whole ? e : 0.5 * e));
        s.axial.friction.push_back(internFriction(s, {ma.interface.friction, ma.interface.tangential_stiffness_N_m}));
      }
    }
    for (int dir = 1; dir <= 2; ++dir) {
      const int b = dir == 1 ? s.nodeAt(i, j + 1, k) : s.nodeAt(i, j, k + 1);
      if (b < 0) continue;
      const auto& mb = s.materials[static_cast<std::size_t>(s.material[static_cast<std::size_t>(b)])];
      s.lateral.a.push_back(a);
      s.lateral.b.push_back(b);
      s.lateral.dir.push_back(dir);
      s.lateral.law.push_back(internAxial(s, seriesAxialLaw(ma.axial, mb.axial), e));
      s.lateral.friction.push_back(internFriction(s, pairFriction(ma, mb)));
    }
    if (k == 0 && spec.support.ground_friction) {
      // (the whole column: a resolved cell above stands on this one, its
      // weight held by the hybrid's plate, and reaches the ground through it)
      double column = 0.0;
      for (int kk = 0; kk < s.nz; ++kk)
        if (const int m = cell_material[static_cast<std::size_t>(i + s.nx * (j + s.ny * kk))]; m >= 0)
          column += s.materials[static_cast<std::size_t>(m)].mass_kg;
      const double mu = spec.support.ground_friction_coefficient >= 0.0 ? spec.support.ground_friction_coefficient
                                                                        : ma.interface.friction;
      const double kt = spec.support.ground_tangential_stiffness_N_m > 0.0
                            ? spec.support.ground_tangential_stiffness_N_m
                            : ma.interface.tangential_stiffness_N_m;
      s.ground.node.push_back(a);
      s.ground.law.push_back(internAxial(s, halfCellLaw(ma.axial), 0.5 * e));
      s.ground.friction.push_back(internFriction(s, {mu, kt}));
      s.ground.weight_N.push_back(column * spec.support.gravity_m_s2);
    }
  }
  for (int k = 0; k < s.nz; ++k)
    for (int j = 0; j < s.ny; ++j) {
      const int i = s.front_offset_cells[static_cast<std::size_t>(k)];
      const int node = s.nodeAt(i, j, k);
      if (node < 0) continue;  // (a resolved cell: the fine scale takes the boulder there)
      s.front.node.push_back(node);
      s.front.law.push_back(
          internAxial(s, s.materials[static_cast<std::size_t>(s.material[static_cast<std::size_t>(node)])].impact, e));
      s.front.x_min.push_back(i * e);
      s.front.y_min.push_back(j * e);
      s.front.z_min.push_back(k * e);
      // A side face is covered by the cell beside it (macro or resolved):
      // one in the grid beside it in y, or in the layer above or below
      // whose front is not set back behind this cell; the bottom layer's
      // underside, by the base the structure stands on.
      const auto covered_z = [&](int kk) {
        return kk < 0 || (kk < s.nz && s.front_offset_cells[static_cast<std::size_t>(kk)] <= i);
      };
      using F = Structure::FrontElements;
      s.front.open_sides.push_back(
          static_cast<unsigned char>((j == 0 ? F::kOpenYMinus : 0) | (j == s.ny - 1 ? F::kOpenYPlus : 0) |
                                     (covered_z(k - 1) ? 0 : F::kOpenZMinus) | (covered_z(k + 1) ? 0 : F::kOpenZPlus)));
    }
  return s;
}

}  // namespace gabion::macro
