#pragma once
/// \file
/// The contact laws of every pair of the scene's materials (mixMaterials and
/// the scene's contact pairs),
/// as a table of PairLaw and as flat arrays that the vector kernels gather
/// from, with the rare features any of them uses: the kernels are compiled
/// without the others (a case pays only for what it uses).
#include <cmath>
#include <cstdint>
#include <vector>

#include "micro/contact.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

/// The laws of every pair of materials (nmat x nmat, row-major): the mixing
/// rule (mixMaterials), then each contact pair's given values, both orders.
inline std::vector<PairLaw> pairLawTable(const std::vector<Material>& materials,
                                         const std::vector<ContactPair>& pairs = {}) {
  const std::size_t n = materials.size();
  std::vector<PairLaw> table(n * n);
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = 0; b < n; ++b) table[a * n + b] = mixMaterials(materials[a], materials[b]);
  for (const ContactPair& p : pairs)
    for (const std::size_t k : {static_cast<std::size_t>(p.a) * n + static_cast<std::size_t>(p.b),
                                static_cast<std::size_t>(p.b) * n + static_cast<std::size_t>(p.a)}) {
      PairLaw& l = table[k];
      if (p.normal_stiffness_N_m) l.normal.stiffness_N_m = *p.normal_stiffness_N_m;
      if (p.shear_stiffness_N_m) l.tangential.stiffness_N_m = *p.shear_stiffness_N_m;
      if (p.friction) l.tangential.friction = *p.friction;
      if (p.normal_force_limit_N) l.normal.force_limit_N = *p.normal_force_limit_N;
      if (p.viscous_damping_ratio) l.damping_ratio = *p.viscous_damping_ratio;
    }
  return table;
}

struct MaterialLaws {
  std::size_t nmat = 0;
  std::vector<PairLaw> pair;                      ///< nmat x nmat, row-major
  std::vector<double> kn, flim, ks, mu_ks, zeta;  ///< per pair; mu_ks = friction / k_s (m/N)
  bool any_plastic = false;                       ///< a finite F_lim
  bool any_viscous = false;                       ///< viscous contact damping
  bool uniform = false;  ///< every particle has one material: the kernels read law0 instead of gathering
  std::uint32_t law0 = 0;

  explicit MaterialLaws(const std::vector<Material>& materials = {}, const std::vector<ContactPair>& pairs = {})
      : nmat(materials.size()), pair(pairLawTable(materials, pairs)) {
    for (const PairLaw& l : pair) {
      kn.push_back(l.normal.stiffness_N_m);
      flim.push_back(l.normal.force_limit_N);
      ks.push_back(l.tangential.stiffness_N_m);
      mu_ks.push_back(l.tangential.friction / l.tangential.stiffness_N_m);
      zeta.push_back(l.damping_ratio);
      any_plastic = any_plastic || std::isfinite(l.normal.force_limit_N);
      any_viscous = any_viscous || l.damping_ratio > 0.0;
    }
  }
  /// Every particle also has one body mass: each pair's dashpot coefficient
  /// is then `uniform_damping`, taken once (the kernel gathers no masses and
  /// takes no square root for it).
  bool uniform_mass = false;
  double uniform_damping = 0.0;  ///< N s/m
  /// Every particle also has one radius (with uniform_mass): the kernel
  /// takes `uniform_radius_m` instead of gathering two radii per pair.
  bool uniform_radius = false;
  double uniform_radius_m = 0.0;

  /// Marks the scene as one of a single material m.
  void setUniform(bool one_material, std::uint32_t m) {
    uniform = one_material;
    law0 = one_material ? m * static_cast<std::uint32_t>(nmat + 1) : 0;
  }
  /// Marks every particle (after setUniform) as one of body mass 1 / inv_mass
  /// (one_mass) or not.
  void setUniformMass(bool one_mass, double inv_mass) {
    uniform_mass = uniform && one_mass;
    uniform_damping = uniform_mass ? bridge::dashpotCoefficient({zeta[law0]}, kn[law0], inv_mass + inv_mass) : 0.0;
  }
  /// Marks every particle (after setUniformMass) as one of radius r (one_radius) or not.
  void setUniformRadius(bool one_radius, double r) {
    uniform_radius = uniform_mass && one_radius;
    uniform_radius_m = uniform_radius ? r : 0.0;
  }
};

}  // namespace gabion::micro
