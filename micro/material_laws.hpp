#pragma once
/// \file
/// The contact laws of every pair of the scene's materials (mixMaterials),
/// as a table of PairLaw and as flat arrays that the vector kernels gather
/// from, with the rare features any of them uses: the kernels are compiled
/// without the others (a case pays only for what it uses).
#include <cmath>
#include <cstdint>
#include <vector>

#include "micro/contact.hpp"
#include "micro/scene.hpp"

namespace gabion::micro {

struct MaterialLaws {
  std::size_t nmat = 0;
  std::vector<PairLaw> pair;                      ///< nmat x nmat, row-major
  std::vector<double> kn, flim, ks, mu_ks, zeta;  ///< per pair; mu_ks = friction / k_s (m/N)
  bool any_plastic = false;                       ///< a finite F_lim
  bool any_viscous = false;                       ///< viscous contact damping
  bool uniform = false;  ///< every particle has one material: the kernels read law0 instead of gathering
  std::uint32_t law0 = 0;

  explicit MaterialLaws(const std::vector<Material>& materials = {}) : nmat(materials.size()) {
    pair.resize(nmat * nmat);
    for (std::size_t a = 0; a < nmat; ++a)
      for (std::size_t b = 0; b < nmat; ++b) pair[a * nmat + b] = mixMaterials(materials[a], materials[b]);
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
  /// Marks the scene as one of a single material m.
  void setUniform(bool one_material, std::uint32_t m) {
    uniform = one_material;
    law0 = one_material ? m * static_cast<std::uint32_t>(nmat + 1) : 0;
  }
};

}  // namespace gabion::micro
