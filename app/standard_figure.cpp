#include "app/standard_figure.hpp"

#include <string>
#include <vector>

#include "bridge/errors.hpp"
#include "bridge/manifest.hpp"
#include "bridge/output.hpp"
#include "bridge/plot.hpp"

namespace gabion::app {

namespace fs = std::filesystem;

namespace {

// The first lab curve the file holds, as force (kN) against its x (mm).
bool labCurve(const bridge::H5Reader& h5, bridge::PlotSpec& spec) {
  struct Kind {
    const char* group;
    const char* x;
    const char* title;
  };
  const Kind kinds[] = {{"/curves/axial", "displacement_m", "Confined compression (CC): axial force"},
                        {"/curves/uc", "displacement_m", "Unconfined compression (UC): axial force"},
                        {"/curves/impact", "penetration_m", "Unconfined impact (UCI): boulder force"},
                        {"/curves/shear", "displacement_m", "Interface shear: tangential force"}};
  for (const Kind& k : kinds) {
    const std::string x = std::string(k.group) + "/" + k.x, y = std::string(k.group) + "/force_N";
    if (!h5.has(x) || !h5.has(y)) continue;
    spec.title = k.title;
    spec.x_label = std::string(k.x) == "penetration_m" ? "penetration (mm)" : "displacement (mm)";
    spec.y_label = "force (kN)";
    spec.series.push_back(bridge::scaledSeries("", h5.read(x), h5.read(y), 1e3, 1e-3));
    return true;
  }
  return false;
}

bool impactSeries(const bridge::H5Reader& h5, bridge::PlotSpec& spec) {
  if (!h5.has("/series/boulder_force_N") || !h5.has("/series/time_s")) return false;
  const auto t = h5.read("/series/time_s"), f = h5.read("/series/boulder_force_N");
  const auto impact = h5.has("/series/impact") ? h5.read("/series/impact") : std::vector<double>(t.size(), 0.0);
  spec.title = "Structure impact: force on the boulder";
  spec.x_label = "time (ms)";
  spec.y_label = "force (kN)";
  for (std::size_t i = 0; i < t.size();) {
    std::vector<double> x, y;
    const double k = impact[i];
    for (; i < t.size() && impact[i] == k; ++i) x.push_back(t[i]), y.push_back(f[i]);
    spec.series.push_back(bridge::scaledSeries("impact " + std::to_string(static_cast<int>(k) + 1), x, y, 1e3, 1e-3));
  }
  if (spec.series.size() == 1) spec.series.front().label.clear();
  return true;
}

bool sweepTable(const bridge::H5Reader& h5, bridge::PlotSpec& spec) {
  if (!h5.has("/table/impact_energy_J") || !h5.has("/table/peak_force_N")) return false;
  spec.title = "Sweep: peak force against impact energy";
  spec.x_label = "impact energy (kJ)";
  spec.y_label = "peak force (kN)";
  spec.series.push_back(bridge::scaledSeries("", h5.read("/table/impact_energy_J"), h5.read("/table/peak_force_N"),
                                             1e-3, 1e-3, bridge::PlotSeries::Style::Markers));
  return true;
}

bool energyLedger(const bridge::H5Reader& h5, bridge::PlotSpec& spec) {
  if (!h5.has("/series/total_J") || !h5.has("/series/time_s")) return false;
  const auto t = h5.read("/series/time_s");
  spec.title = "Fine DEM: energy ledger";
  spec.x_label = "time (s)";
  spec.y_label = "energy (J)";
  for (const char* name : {"kinetic_translational_J", "elastic_contact_J", "gravity_potential_J",
                           "friction_dissipation_J", "local_damping_dissipation_J", "total_J"}) {
    const std::string ds = std::string("/series/") + name;
    if (!h5.has(ds)) continue;
    std::string label = name;
    label = label.substr(0, label.size() - 2);
    for (auto& c : label) c = c == '_' ? ' ' : c;
    spec.series.push_back({label, t, h5.read(ds)});
  }
  return true;
}

}  // namespace

void writeStandardFigure(const fs::path& result, const fs::path& figure) {
  if (!fs::exists(result)) throw bridge::InputError(result.string(), "", "file does not exist");
  if (!fs::is_regular_file(result)) throw bridge::InputError(result.string(), "", "not a regular file");
  bridge::requireListed(result);  // (a result of the run that wrote its folder, complete)
  bridge::PlotSpec spec;
  {
    const bridge::H5Reader h5(result);
    if (!labCurve(h5, spec) && !impactSeries(h5, spec) && !sweepTable(h5, spec) && !energyLedger(h5, spec))
      throw bridge::InputError(result.string(), "",
                               "no standard figure for this file: it holds no lab curve (/curves), structure impact "
                               "(/series/boulder_force_N), sweep table (/table) or energy ledger (/series/total_J)");
  }
  if (figure.extension() == ".svg")
    bridge::writePlotSvg(figure, spec);
  else
    bridge::writePlotPng(figure, spec);
}

}  // namespace gabion::app
