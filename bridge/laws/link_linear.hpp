#pragma once
/// \file
/// Linear link: a force between two particles that depends on their distance
/// only (a "remote interaction"), F = k (L - L0), positive in tension; with
/// `tension_only` it acts only in tension (a slack wire), and it breaks for
/// good once its strain (L - L0) / L0 passes `rupture_strain`. The fine DEM's
/// link stage (micro/links.hpp) evaluates it; the wire law of the netting
/// takes the same place.
#include <cmath>
#include <limits>

namespace gabion::bridge {

struct LinearLinkParams {
  double stiffness_N_m = 0.0;                                       ///< k (N/m), > 0
  double rest_length_m = 0.0;                                       ///< L0 (m), > 0
  bool tension_only = false;                                        ///< no force in compression
  double rupture_strain = std::numeric_limits<double>::infinity();  ///< breaks above this strain (-)
};

/// The link's response at length L (m).
struct LinkResponse {
  double force_N = 0.0;    ///< tension > 0 (pulls the ends together), compression < 0
  double elastic_J = 0.0;  ///< stored energy
  bool breaks = false;     ///< strain above the rupture strain: the link stops acting
};

inline LinkResponse linearLinkResponse(const LinearLinkParams& p, double length_m) {
  const double stretch = length_m - p.rest_length_m;
  const bool acts = !p.tension_only || stretch > 0.0;
  LinkResponse out;
  out.breaks = stretch > p.rupture_strain * p.rest_length_m;
  out.force_N = acts && !out.breaks ? p.stiffness_N_m * stretch : 0.0;
  out.elastic_J = acts && !out.breaks ? 0.5 * p.stiffness_N_m * stretch * stretch : 0.0;
  return out;
}

}  // namespace gabion::bridge
