#include "micro/blocks/block_fill.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "bridge/plot.hpp"
#include "micro/blocks/angular_block.hpp"
#include "micro/blocks/grading.hpp"
#include "micro/particles.hpp"
#include "micro/rigid_body.hpp"

namespace gabion::micro {
namespace {

using bridge::Check;
using bridge::JsonReader;

// One of the 8 rotations that lay a block flat (its short edge vertical, its
// long edge along x or y, either way up), drawn with the generator: its box is
// known, so blocks can be packed side by side; they turn as they fall.
Eigen::Quaterniond flatRotation(std::mt19937_64& rng) {
  const unsigned k = static_cast<unsigned>(rng() % 8);
  const double quarter = 0.5 * 3.14159265358979323846;
  const Eigen::Quaterniond about_z(Eigen::AngleAxisd(quarter * (k % 4), Eigen::Vector3d::UnitZ()));
  const Eigen::Quaterniond flip(Eigen::AngleAxisd(k >= 4 ? 2.0 * quarter : 0.0, Eigen::Vector3d::UnitX()));
  return about_z * flip;
}

BlockShape parseShape(const JsonReader& r) {
  BlockShape s;
  const auto o = r.optionalObject("shape");
  if (!o) return s;
  s.long_ratio = o->number("long_ratio", s.long_ratio, Check::Positive);
  s.short_ratio = o->number("short_ratio", s.short_ratio, Check::Positive);
  s.spheres_along_long = static_cast<int>(o->integer("spheres_along_long", s.spheres_along_long, 1));
  s.spacing_ratio = o->number("spacing_ratio", s.spacing_ratio, Check::Positive);
  s.cut = o->number("cut", s.cut, Check::NonNegative);
  const BlockShapeIssue issue = checkBlockShape(s);
  if (!issue.key.empty()) o->fail(issue.key, issue.message);
  return s;
}

}  // namespace

nlohmann::json addBlockFill(const JsonReader& r, Scene& scene, int material, const Vec3& lo, const Vec3& hi,
                            double target, std::uint64_t seed,
                            const std::function<void(const std::string&)>& too_small) {
  const double density = scene.materials[static_cast<std::size_t>(material)].density_kg_m3;
  const BlockShape shape = parseShape(r);
  // A block of size d has the mass of the unit block times d^3 (one shape).
  const BlockGeometry unit = angularBlock(shape, 1.0);
  const double unit_mass = clusterMassProperties(unit.centers_m, unit.radii_m, density).mass_kg;
  const auto mass_of = [&](double d) { return unit_mass * d * d * d; };
  std::vector<double> sizes;
  GradingTable table;
  const bool graded = r.has("grading");
  if (graded == r.has("gaussian")) r.failHere("give either a `grading` table or a `gaussian` of the block size");
  if (graded) {
    const JsonReader g = r.object("grading");
    table.sieve_m = g.numbers("sieve_m", Check::Positive, 2);
    table.passing_percent = g.numbers("passing_percent", Check::NonNegative, 2);
    const GradingIssue issue = checkGrading(table);
    if (!issue.key.empty()) {
      if (issue.at < 0) g.fail(issue.key, issue.message);
      g.failElement(issue.key, static_cast<std::size_t>(issue.at), issue.message);
    }
    sizes = sampleGrading(table, target, mass_of, seed);
  } else {
    const JsonReader g = r.object("gaussian");
    const double mean = g.number("mean_m", Check::Positive), sd = g.number("sd_m", Check::NonNegative);
    sizes = sampleGaussian(mean, sd, target, mass_of, seed);
    // Report it against sieves spanning the sample.
    for (int k = 0; k <= 6; ++k) table.sieve_m.push_back(std::max(0.2 * mean, mean - 2.5 * sd) + k * 5.0 * sd / 6.0);
  }
  if (sizes.empty()) r.failHere("the mass of rock is below half a block: no block to place");
  // Largest first, layer by layer: rows along x, rows stacked along y,
  // layers up z, each block laid flat in its box with a gap of 2 % of its size.
  std::sort(sizes.begin(), sizes.end(), std::greater<>());
  std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ull);
  double x = lo.x(), y = lo.y(), z = lo.z(), row = 0.0, layer = 0.0;
  const int group = static_cast<int>(r.integer("group", 0, 0));
  if (group >= kGroupCount) r.fail("group", "contact groups are 0 .. " + std::to_string(kGroupCount - 1));
  std::vector<double> masses;
  double mass = 0.0;
  for (std::size_t b = 0; b < sizes.size(); ++b) {
    const BlockGeometry geom = angularBlock(shape, sizes[b]);
    const Eigen::Quaterniond q = flatRotation(rng);
    const Vec3 box = (q.toRotationMatrix().cwiseAbs() * geom.edges_m).array() + 0.02 * sizes[b];
    if (x + box.x() > hi.x() + 1e-12) x = lo.x(), y += row, row = 0.0;
    if (y + box.y() > hi.y() + 1e-12) x = lo.x(), y = lo.y(), z += layer, row = layer = 0.0;
    if (x + box.x() > hi.x() + 1e-12 || y + box.y() > hi.y() + 1e-12 || z + box.z() > hi.z() + 1e-12)
      too_small("the region holds " + std::to_string(b) + " of the " + std::to_string(sizes.size()) +
                " blocks (packed side by side in their boxes, layer by layer): make it taller, or ask for less rock");
    BlockSpec spec;
    spec.member_centers_m = geom.centers_m;
    spec.member_radii_m = geom.radii_m;
    spec.material = material;
    spec.group = group;
    spec.position_m = Vec3(x, y, z) + 0.5 * box;
    spec.orientation = q;
    scene.blocks.push_back(spec);
    masses.push_back(mass_of(sizes[b]));
    mass += masses.back();
    x += box.x(), row = std::max(row, box.y()), layer = std::max(layer, box.z());
  }
  nlohmann::json rep;
  rep["blocks"] = sizes.size();
  rep["mass_kg"] = mass;
  rep["target_mass_kg"] = target;
  rep["sieve_m"] = table.sieve_m;
  if (graded) rep["target_passing_percent"] = table.passing_percent;
  rep["passing_percent"] = passingPercent(sizes, masses, table.sieve_m);
  rep["spheres_per_block"] = unit.centers_m.size();
  return rep;
}

nlohmann::json addBlockFills(const JsonReader& root, Scene& scene) {
  nlohmann::json reports = nlohmann::json::array();
  const std::vector<JsonReader> fills = root.objects("block_fills");
  for (std::size_t f = 0; f < fills.size(); ++f) {
    const JsonReader& r = fills[f];
    // Material, by name.
    const std::string name = r.string("material");
    const auto mat =
        std::find_if(scene.materials.begin(), scene.materials.end(), [&](const Material& m) { return m.name == name; });
    if (mat == scene.materials.end()) r.fail("material", "unknown material '" + name + "'");
    const int material = static_cast<int>(mat - scene.materials.begin());
    // The region and the mass of rock to put in it.
    const JsonReader region = r.object("region");
    const Vec3 lo = region.vec3("min_m"), hi = region.vec3("max_m");
    if (!((hi - lo).minCoeff() > 0.0)) region.fail("max_m", "must exceed min_m in x, y and z");
    const bool by_mass = r.has("mass_kg");
    if (by_mass == r.has("solid_fraction"))
      r.failHere("give either `mass_kg` or `solid_fraction` (of the region's volume)");
    double target = 0.0;
    if (by_mass) {
      target = r.number("mass_kg", Check::Positive);
    } else {
      const double fraction = r.number("solid_fraction", Check::Positive);
      if (fraction >= 1.0) r.fail("solid_fraction", "must be below 1");
      target = fraction * mat->density_kg_m3 * (hi - lo).prod();
    }
    const std::uint64_t seed = r.seed("seed", 1);
    reports.push_back(
        addBlockFill(r, scene, material, lo, hi, target, seed, [&](const std::string& m) { region.failHere(m); }));
  }
  return reports;
}

std::vector<std::string> writeGradingFigures(const std::filesystem::path& outdir, const nlohmann::json& reports) {
  std::vector<std::string> files;
  for (std::size_t k = 0; k < reports.size(); ++k) {
    const nlohmann::json& rep = reports[k];
    bridge::PlotSpec plot;
    plot.title = "Block fill " + std::to_string(k) + ": grading made against its target";
    plot.x_label = "sieve size (mm)";
    plot.y_label = "passing by mass (%)";
    std::vector<double> mm;
    for (const double s : rep["sieve_m"].get<std::vector<double>>()) mm.push_back(1000.0 * s);
    if (rep.contains("target_passing_percent"))
      plot.series.push_back({"target", mm, rep["target_passing_percent"].get<std::vector<double>>(),
                             bridge::PlotSeries::Style::LineMarkers});
    plot.series.push_back({"made (" + std::to_string(rep["blocks"].get<std::size_t>()) + " blocks)", mm,
                           rep["passing_percent"].get<std::vector<double>>(), bridge::PlotSeries::Style::Markers});
    const std::string name = "grading_" + std::to_string(k) + ".png";
    bridge::writePlotPng(outdir / name, plot);
    files.push_back(name);
  }
  return files;
}

}  // namespace gabion::micro
