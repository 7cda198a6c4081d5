#pragma once
/// \file
/// Reading the macro case kinds (`macro.impact`, `macro.sweep`) from a
/// validated JSON document: laws (embedded or a law file), structure,
/// boulder, impacts, run settings. Formats in docs/macro.md.
#include <array>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"
#include "bridge/law_file.hpp"
#include "bridge/run.hpp"
#include "macro/impact.hpp"
#include "macro/structure.hpp"

namespace gabion::macro {

/// A macro.impact case, read and validated.
struct ImpactCase {
  bridge::LawFile laws;
  std::string law_source;  ///< "embedded" or the law file's path
  StructureSpec structure;
  std::vector<BoulderSpec> impacts;  ///< at least one
  std::vector<bool> aim_given;       ///< per impact: aim point from the case (else the default aim)
  RunSettings run;
};

/// One sweep axis: values in the order given.
struct SweepSpec {
  std::vector<double> velocity_m_s;  ///< speeds along the boulder's direction; empty: the case's
  std::vector<double> mass_kg;       ///< boulder masses; empty: the case's
  bool keep_diameter = false;        ///< a mass changes the boulder's density, not (at its density) its diameter
  std::vector<std::pair<double, double>> aim_point_m;  ///< (y, z); empty: the case's aim
  std::vector<std::array<int, 3>> cells;               ///< structure sizes (x, y, z); empty: the case's
  bool chart = true;                                   ///< write the design charts
  /// Limit lines on the charts (`limits`; infinity: none).
  double limit_peak_force_N = std::numeric_limits<double>::infinity();
  double limit_penetration_m = std::numeric_limits<double>::infinity();
  double limit_back_face_m = std::numeric_limits<double>::infinity();
};

/// Reads the laws (embedded, or the case's `law_file`: `gabion run --law`
/// sets that key), structure, boulder and run of a macro case; every
/// material the structure names must be in its laws. With `sweep` the case
/// may not list impacts and does not relax after the impact. Throws InputError.
ImpactCase readImpactCase(const bridge::JsonDocument& doc, bool sweep);
/// The most steps an impact may take (it ends at its outcome: a few
/// thousand on the default wall).
constexpr double kMaxImpactSteps = 1e7;

/// Refuses (InputError on /run/duration_s or /run/max_duration_s) an impact
/// whose longest run, max_duration_s at its time step (from `critical_s`, the
/// structure's critical step with the boulder placed), would pass
/// kMaxImpactSteps, with the steps and the memory its series would take.
void checkImpactCost(const bridge::JsonDocument& doc, const RunSettings& run, const Structure& s, double critical_s);
/// What one impact on `s` costs at most (bridge/cost.hpp): its cells, the
/// steps up to run.max_duration_s, the series samples it records.
bridge::Estimate impactEstimate(const RunSettings& run, const Structure& s, double critical_s);

/// Reads the "sweep" object of a macro.sweep case.
SweepSpec readSweep(const bridge::JsonReader& sweep);
/// Builds the structure of a case; an inconsistency (unknown material, mixed
/// cell sizes, wrong list length) is an InputError on /structure.
Structure buildCaseStructure(const bridge::JsonDocument& doc, const ImpactCase& c);

/// Fills the default aim points and checks the given ones lie on the front
/// face (InputError on their key otherwise).
void resolveAims(const bridge::JsonDocument& doc, ImpactCase& c, const Structure& s);

/// The default aim point: the centre of the front face of the middle cell of
/// the front face (cell ny/2, nz/2, integer division) (m).
std::pair<double, double> defaultAim(const StructureSpec& s, double edge_m);

}  // namespace gabion::macro
