#include "fitting/case_input.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"

namespace gabion::fitting {

namespace fs = std::filesystem;
using bridge::Check;
using bridge::JsonReader;

fs::path caseDirectory(const bridge::JsonDocument& doc) {
  return fs::path(doc.file()).parent_path();
}

WallCurve readWallCurve(const JsonReader& w) {
  if (w.has("index")) {
    // Cases written for gabion.micro.scene/1 named walls by their position in
    // the micro case's "walls"; an unnamed wall is now "wall_<index>".
    const auto it = w.value().find("index");
    const bool count = it->is_number_integer() && it->get<long long>() >= 0;
    const std::string unnamed = count ? "wall_" + std::to_string(it->get<long long>()) : "wall_<index>";
    w.fail("index",
           "walls are read by name, not index: give \"name\", the wall's \"name\" in the micro case "
           "(e.g. \"lid\"; an unnamed wall is \"" +
               unnamed + "\")");
  }
  WallCurve c;
  c.name = w.string("name");
  if (!bridge::isWallName(c.name))
    w.fail("name", "a wall name uses letters, digits, '_' and '-' only (as in the micro case)");
  c.direction = w.vec3("direction");
  if (!(c.direction.norm() > 0.0)) w.fail("direction", "must be a non-zero vector");
  return c;
}

CurveSource readCurveSource(const JsonReader& r, const CurveDefaults& d, std::size_t index, const fs::path& base_dir) {
  CurveSource s;
  s.pointer = r.pointer();
  s.file = base_dir / r.string("file");
  const std::string ext = s.file.extension().string();
  const bool h5 = ext == ".h5" || ext == ".hdf5";
  if (!h5 && ext != ".csv") r.fail("file", "must end in .csv, .h5 or .hdf5");
  s.request.x_name = r.string("x_column", d.x_name);
  s.request.y_name = r.string("y_column", d.y_name);
  s.request.path = r.choice("path", {"monotonic", "cyclic"}, "monotonic") == "cyclic" ? bridge::CurvePath::Cyclic
                                                                                      : bridge::CurvePath::Monotonic;
  s.request.min_points = static_cast<std::size_t>(r.integer("min_points", 5, 3));
  s.replicate = r.string("replicate", d.replicate_per_curve ? std::to_string(index) : "all");
  if (!d.condition_key.empty() && r.has(d.condition_key)) s.condition = r.number(d.condition_key, Check::Positive);
  if (!h5) {
    for (const char* k : {"x_dataset", "y_dataset", "t_dataset", "wall"})
      if (r.has(k)) r.fail(k, "only for HDF5 curve files");
    s.t_column = r.string("t_column", "");
    if (!d.condition_key.empty() && !s.condition) r.fail(d.condition_key, "required for a CSV curve of this test");
    s.kind = CurveSource::Kind::Csv;
    return s;
  }
  if (r.has("t_column")) r.fail("t_column", "only for CSV curve files (an HDF5 curve's is t_dataset)");
  if (auto w = r.optionalObject("wall")) {
    if (r.has("x_dataset") || r.has("y_dataset")) r.fail("wall", "give either \"wall\" or datasets, not both");
    if (r.has("t_dataset")) r.fail("t_dataset", "only with x_dataset and y_dataset");
    s.kind = CurveSource::Kind::H5Wall;
    s.wall = readWallCurve(*w);
    if (!d.condition_key.empty() && !s.condition) r.fail(d.condition_key, "required for a wall curve");
    return s;
  }
  s.kind = CurveSource::Kind::H5Datasets;
  s.x_dataset = r.string("x_dataset", d.h5_group + "/" + s.request.x_name);
  s.y_dataset = r.string("y_dataset", d.h5_group + "/" + s.request.y_name);
  // A dataset named without its column name names the curve's axes (a
  // chart of /curves/impact/indentation_m says "indentation").
  const auto leaf = [](const std::string& path) { return path.substr(path.find_last_of('/') + 1); };
  if (r.has("x_dataset") && !r.has("x_column")) s.request.x_name = leaf(s.x_dataset);
  if (r.has("y_dataset") && !r.has("y_column")) s.request.y_name = leaf(s.y_dataset);
  s.t_dataset = r.string("t_dataset", "");
  if (!d.condition_key.empty()) s.condition_dataset = d.h5_group + "/" + d.condition_key;
  return s;
}

namespace {

// The time axis of curve `c` read from `where` (a dataset or a column of
// s.file): one value per point, strictly increasing.
void attachTime(bridge::Curve& c, const CurveSource& s, const std::string& where, std::vector<double> t,
                const std::vector<std::size_t>& lines) {
  const std::string file = s.file.string();
  if (t.size() != c.size())
    throw bridge::InputError(file, where,
                             "has " + std::to_string(t.size()) + " values for a curve of " + std::to_string(c.size()));
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t[i]))
      throw bridge::InputError(file, where, "value " + std::to_string(i + 1) + " is not finite");
    if (i > 0 && !(t[i] > t[i - 1]))
      throw bridge::InputError(
          file, where + (lines.empty() ? "" : ", line " + std::to_string(lines[i])),
          "must increase strictly (the time of point " + std::to_string(i + 1) + " is not after the one before)");
  }
  c.t = std::move(t);
}

}  // namespace

bridge::Curve loadCurve(const CurveSource& s) {
  switch (s.kind) {
    case CurveSource::Kind::Csv: {
      bridge::Curve c = bridge::readCurveCsv(s.file, s.request);
      if (!s.t_column.empty()) {
        const bridge::CsvTable t = bridge::readCsvTable(s.file, {s.t_column});
        attachTime(c, s, "column " + s.t_column, t.columns.at(s.t_column), t.lines);
      }
      return c;
    }
    case CurveSource::Kind::H5Datasets: {
      bridge::Curve c = bridge::readCurveH5(s.file, s.x_dataset, s.y_dataset, s.request);
      if (!s.t_dataset.empty()) {
        bridge::H5Reader h5(s.file);
        if (!h5.has(s.t_dataset)) throw bridge::InputError(s.file.string(), s.t_dataset, "no such dataset");
        attachTime(c, s, s.t_dataset, h5.read(s.t_dataset), {});
      }
      return c;
    }
    case CurveSource::Kind::H5Wall:
      return bridge::readWallCurveH5(s.file, s.wall.name, s.wall.direction, s.request);
  }
  return {};
}

double curveCondition(const CurveSource& s) {
  if (s.condition) return *s.condition;
  if (s.condition_dataset.empty()) return 0.0;
  bridge::H5Reader h5(s.file);
  if (!h5.has(s.condition_dataset))
    throw bridge::InputError(s.file.string(), s.condition_dataset,
                             "no such dataset: give the value in the case (" + s.pointer + ")");
  const auto v = h5.read(s.condition_dataset);
  double mean = 0.0;
  for (double x : v) mean += x / static_cast<double>(v.size());
  if (v.empty() || !std::isfinite(mean) || !(mean > 0.0))
    throw bridge::InputError(s.file.string(), s.condition_dataset, "must hold finite positive values");
  return mean;
}

OptimizerSettings readOptimizer(const std::optional<JsonReader>& r, unsigned long seed,
                                const OptimizerSettings& defaults) {
  OptimizerSettings s = defaults;
  s.seed = seed;
  if (!r) return s;
  s.global_algorithm = r->string("global", s.global_algorithm);
  if (s.global_algorithm != "none" && !isNloptAlgorithm(s.global_algorithm, true))
    r->fail("global", "unknown global algorithm '" + s.global_algorithm +
                          "' (GN_DIRECT, GN_DIRECT_L, GN_DIRECT_L_RAND, GN_CRS2_LM, GN_ISRES, GN_ESCH or none)");
  s.local_algorithm = r->string("local", s.local_algorithm);
  if (s.local_algorithm != "none" && !isNloptAlgorithm(s.local_algorithm, false))
    r->fail("local", "unknown local algorithm '" + s.local_algorithm +
                         "' (LN_SBPLX, LN_BOBYQA, LN_NELDERMEAD, LN_COBYLA, LN_NEWUOA_BOUND or none)");
  if (s.global_algorithm == "none" && s.local_algorithm == "none")
    r->fail("local", "global and local cannot both be 'none'");
  s.global_max_evaluations = static_cast<int>(r->integer("global_max_evaluations", s.global_max_evaluations, 1));
  s.local_max_evaluations = static_cast<int>(r->integer("local_max_evaluations", s.local_max_evaluations, 1));
  s.xtol_rel = r->number("xtol_rel", s.xtol_rel, Check::Positive);
  s.ftol_rel = r->number("ftol_rel", s.ftol_rel, Check::Positive);
  s.penalty = r->number("penalty", s.penalty, Check::Positive);
  return s;
}

LossSettings readLoss(const std::optional<JsonReader>& r, std::size_t& grid_points) {
  LossSettings l;
  if (!r) return l;
  const std::string kind = r->choice("loss", {"soft_l1", "huber", "l2"}, "soft_l1");
  l.kind = kind == "l2"      ? LossSettings::Kind::L2
           : kind == "huber" ? LossSettings::Kind::Huber
                             : LossSettings::Kind::SoftL1;
  l.scale = r->number("loss_scale", l.scale, Check::Positive);
  grid_points = static_cast<std::size_t>(r->integer("grid_points", static_cast<long long>(grid_points), 10));
  return l;
}

std::vector<CaseParameter> readCaseParameters(const JsonReader& root, const std::string& set_example,
                                              bool name_required) {
  const auto params = root.objects("parameters", true);
  if (params.empty()) root.fail("parameters", "at least one parameter is required");
  std::vector<CaseParameter> out;
  for (const auto& p : params) {
    CaseParameter cp;
    const std::string name = name_required ? p.string("name") : std::string();
    const auto b = p.numbers("bounds", Check::Finite, 2);
    if (b.size() != 2 || !(b[1] > b[0])) p.fail("bounds", "must be [lower, upper] with upper > lower");
    const std::string scale = p.choice("scale", {"auto", "log", "linear"}, "auto");
    if (scale == "log" && !(b[0] > 0.0)) p.fail("scale", "a log scale needs a positive lower bound");
    const nlohmann::json& set = p.raw("set");
    if (set.is_string()) {
      cp.set.push_back(set.get<std::string>());
    } else if (set.is_array() && !set.empty()) {
      for (const auto& s : set) {
        if (!s.is_string()) p.fail("set", "must be a key path or an array of key paths");
        cp.set.push_back(s.get<std::string>());
      }
    } else {
      p.fail("set", "must be a key path (\"" + set_example + "\") or an array of them");
    }
    cp.param = makeParameter(name_required ? name : p.string("name", cp.set.front()), b[0], b[1]);
    if (scale != "auto") cp.param.log_scale = scale == "log";
    out.push_back(std::move(cp));
  }
  return out;
}

std::string fullPrecision(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}

bridge::JsonDocument withParameters(const bridge::JsonDocument& base, const std::vector<CaseParameter>& params,
                                    const std::vector<double>& values) {
  bridge::JsonDocument doc(base.json(), base.file());
  for (std::size_t i = 0; i < params.size(); ++i)
    for (const auto& path : params[i].set) doc.applySet(path + "=" + fullPrecision(values[i]));
  return doc;
}

std::vector<double> midpoint(const std::vector<CaseParameter>& params) {
  std::vector<double> v;
  for (const auto& p : params) v.push_back(fromUnit(p.param, 0.5));
  return v;
}

bool setPathMatches(const std::string& set, const std::string& pointer) {
  std::string path = "/" + set;
  std::replace(path.begin(), path.end(), '.', '/');
  return !pointer.empty() && (pointer.rfind(path, 0) == 0 || path.rfind(pointer, 0) == 0);
}

Bounds readBounds(const JsonReader& r, const std::vector<std::string>& names) {
  Bounds b;
  for (const auto& name : names) {
    const auto v = r.numbers(name, Check::Finite, 2);
    if (v.size() != 2) r.fail(name, "must be [lower, upper]");
    if (!(v[1] > v[0])) r.fail(name, "upper bound must exceed lower bound");
    b[name] = {v[0], v[1]};
  }
  return b;
}

}  // namespace gabion::fitting
