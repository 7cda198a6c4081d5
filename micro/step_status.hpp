#pragma once
/// \file
/// What one step of the fine DEM ended with. Numerical trouble is a status,
/// never an exception: the run reports it (Engine::failure() says what, when
/// and which bodies) and stops, keeping what it wrote.
namespace gabion::micro {

enum class StepStatus {
  Ok,
  NonFinite,      ///< a position, velocity or force became NaN or infinite
  Overlap,        ///< a contact overlap passed run.max_overlap_ratio of the smaller radius
  EnergyRunaway,  ///< kinetic + elastic energy grew past run.energy_runaway_factor x the energy supplied
  Tunnelling,     ///< a body moved more than the smallest radius in one step: it can pass through others unseen
  EnergyBalance,  ///< the energy balance error passed run.max_balance_error: the integration is not to be trusted
};

/// A short name of the status ("ok", "non_finite", "overlap", "energy_runaway", "tunnelling", "energy_balance").
inline const char* statusName(StepStatus s) {
  switch (s) {
    case StepStatus::Ok:
      return "ok";
    case StepStatus::NonFinite:
      return "non_finite";
    case StepStatus::Overlap:
      return "overlap";
    case StepStatus::EnergyRunaway:
      return "energy_runaway";
    case StepStatus::Tunnelling:
      return "tunnelling";
    case StepStatus::EnergyBalance:
      return "energy_balance";
  }
  return "unknown";
}

}  // namespace gabion::micro
