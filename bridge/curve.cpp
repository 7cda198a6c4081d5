#include "bridge/curve.hpp"

#include <H5Cpp.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

#include "bridge/errors.hpp"
#include "bridge/output.hpp"

namespace gabion::bridge {

namespace fs = std::filesystem;

namespace {

// micro.scene results keep one group per named wall here (docs/formats.md).
constexpr const char* kWallsGroup = "/series/walls";
constexpr const char* kSceneFormat = "gabion.micro.scene/2";

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> splitCells(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

// "displacement_m" -> {"displacement", "m"}: the unit is the part after the last '_'.
std::pair<std::string, std::string> stemAndUnit(const std::string& name) {
  const auto pos = name.rfind('_');
  if (pos == std::string::npos) return {name, ""};
  return {name.substr(0, pos), name.substr(pos + 1)};
}

std::string location(std::size_t line, std::size_t column, const std::string& name) {
  std::string s = "line " + std::to_string(line);
  if (column > 0) s += ", column " + std::to_string(column) + (name.empty() ? "" : " (" + name + ")");
  return s;
}

// Finds `wanted` in the header; a column with the same stem but another unit
// (displacement_mm for displacement_m, "displacement (mm)") is a unit error.
std::size_t findColumn(const std::string& file, const std::vector<std::string>& header, const std::string& wanted,
                       std::size_t header_line) {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == wanted) return i;
  const auto [stem, unit] = stemAndUnit(wanted);
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string& h = header[i];
    if (h.rfind(stem, 0) == 0 && h.size() > stem.size()) {
      const char sep = h[stem.size()];
      if (sep == '_' || sep == ' ' || sep == '(' || sep == '[')
        throw InputError(file, location(header_line, i + 1, h),
                         "column '" + h + "' has the wrong unit: expected '" + wanted + "' (SI unit '" + unit +
                             "' as the name's suffix)");
    }
  }
  std::string have;
  for (const auto& h : header) have += (have.empty() ? "" : ", ") + h;
  throw InputError(file, location(header_line, 0, ""), "missing column '" + wanted + "' (header has: " + have + ")");
}

bool parseNumber(const std::string& cell, double& value) {
  if (cell.empty()) return false;
  errno = 0;
  char* end = nullptr;
  value = std::strtod(cell.c_str(), &end);
  return end == cell.c_str() + cell.size() && errno != ERANGE;
}

}  // namespace

void validateCurve(const Curve& c, const CurveRequest& request, const std::vector<std::size_t>& lines,
                   std::size_t x_column, std::size_t y_column) {
  const auto lineOf = [&](std::size_t i) { return lines.empty() ? i + 1 : lines[i]; };
  if (c.x.size() != c.y.size())
    throw InputError(
        c.source, "",
        "x and y have different lengths (" + std::to_string(c.x.size()) + " and " + std::to_string(c.y.size()) + ")");
  if (c.x.size() < request.min_points)
    throw InputError(c.source, c.x.empty() ? "" : location(lineOf(c.x.size() - 1), 0, ""),
                     "curve too short: " + std::to_string(c.x.size()) + " points, at least " +
                         std::to_string(request.min_points) + " required");
  for (std::size_t i = 0; i < c.x.size(); ++i) {
    if (!std::isfinite(c.x[i]))
      throw InputError(c.source, location(lineOf(i), x_column, c.x_name), "value is not finite (NaN or infinite)");
    if (!std::isfinite(c.y[i]))
      throw InputError(c.source, location(lineOf(i), y_column, c.y_name), "value is not finite (NaN or infinite)");
    if (request.path == CurvePath::Monotonic && i > 0 && c.x[i] < c.x[i - 1])
      throw InputError(c.source, location(lineOf(i), x_column, c.x_name),
                       "unsorted: " + c.x_name +
                           " decreases from the previous row (a monotonic loading curve is "
                           "required; declare \"path\": \"cyclic\" for loading/unloading curves)");
  }
  double lo = c.x[0], hi = c.x[0];
  for (double v : c.x) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!(hi > lo))
    throw InputError(c.source, location(lineOf(0), x_column, c.x_name), "column has no spread (all values equal)");
}

CsvTable readCsvTable(const fs::path& file, const std::vector<std::string>& required,
                      const std::vector<std::string>& optional) {
  const std::string name = file.string();
  std::error_code ec;
  if (!fs::exists(file, ec)) throw InputError(name, "", "file does not exist");
  if (!fs::is_regular_file(file, ec)) throw InputError(name, "", "not a regular file");
  std::ifstream in(file);
  if (!in) throw InputError(name, "", "cannot open file");

  std::string line;
  std::size_t line_no = 0;
  CsvTable t;
  t.source = name;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string s = trim(line);
    if (s.empty() || s[0] == '#') continue;
    t.header = splitCells(s);
    t.header_line = line_no;
    break;
  }
  if (t.header.empty())
    throw InputError(name, location(std::max<std::size_t>(line_no, 1), 0, ""), "empty file: no header line");
  std::vector<std::size_t> read;  // the columns read, by index, each once
  for (const auto& want : required) {
    const std::size_t i = findColumn(name, t.header, want, t.header_line);
    if (std::find(read.begin(), read.end(), i) == read.end()) read.push_back(i);
    t.columns[want];
  }
  for (const auto& want : optional)
    for (std::size_t i = 0; i < t.header.size(); ++i)
      if (t.header[i] == want && std::find(read.begin(), read.end(), i) == read.end()) {
        read.push_back(i);
        t.columns[want];
      }

  while (std::getline(in, line)) {
    ++line_no;
    const std::string s = trim(line);
    if (s.empty() || s[0] == '#') continue;
    const auto cells = splitCells(s);
    if (cells.size() != t.header.size())
      throw InputError(
          name, location(line_no, std::min(cells.size(), t.header.size()) + 1, ""),
          "row has " + std::to_string(cells.size()) + " cells, the header has " + std::to_string(t.header.size()));
    for (const std::size_t col : read) {
      double v = 0.0;
      if (!parseNumber(cells[col], v))
        throw InputError(name, location(line_no, col + 1, t.header[col]), "not a number: '" + cells[col] + "'");
      if (!std::isfinite(v))
        throw InputError(name, location(line_no, col + 1, t.header[col]), "value is not finite (" + cells[col] + ")");
      t.columns[t.header[col]].push_back(v);
    }
    t.lines.push_back(line_no);
  }
  if (t.lines.empty()) throw InputError(name, location(line_no, 0, ""), "empty file: a header but no data rows");
  return t;
}

std::size_t CsvTable::column(const std::string& name) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return i + 1;
  return 0;
}

std::string CsvTable::where(std::size_t row, const std::string& name) const {
  return location(lines.at(row), column(name), name);
}

Curve readCurveCsv(const fs::path& file, const CurveRequest& request) {
  const CsvTable t = readCsvTable(file, {request.x_name, request.y_name}, {"time_s"});
  if (t.columns.count("time_s") != 0) {
    const auto& time = t.columns.at("time_s");
    for (std::size_t i = 1; i < time.size(); ++i)
      if (!(time[i] > time[i - 1]))
        throw InputError(t.source, t.where(i, "time_s"), "unsorted: time_s must increase strictly");
  }
  Curve c;
  c.source = t.source;
  c.x_name = request.x_name;
  c.y_name = request.y_name;
  c.x = t.columns.at(request.x_name);
  c.y = t.columns.at(request.y_name);
  validateCurve(c, request, t.lines, t.column(request.x_name), t.column(request.y_name));
  return c;
}

Curve readCurveH5(const fs::path& file, const std::string& x_dataset, const std::string& y_dataset,
                  const CurveRequest& request) {
  H5Reader h5(file);
  Curve c;
  c.source = file.string() + ":" + x_dataset + "," + y_dataset;
  c.x_name = request.x_name;
  c.y_name = request.y_name;
  for (const auto& ds : {x_dataset, y_dataset}) {
    if (!h5.has(ds)) throw InputError(file.string(), ds, "no such dataset (see docs/fitting.md for the curve names)");
    if (h5.dims(ds).size() != 1) throw InputError(file.string(), ds, "must be a 1-D dataset");
    const std::string unit = h5.attribute(ds, "unit");
    const std::string want = stemAndUnit(ds == x_dataset ? request.x_name : request.y_name).second;
    if (!unit.empty() && unit != want)
      throw InputError(file.string(), ds, "dataset has unit '" + unit + "', expected '" + want + "'");
  }
  c.x = h5.read(x_dataset);
  c.y = h5.read(y_dataset);
  validateCurve(c, request, {});
  return c;
}

bool isWallName(const std::string& name) {
  return !name.empty() && name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") ==
                              std::string::npos;
}

std::vector<std::string> wallNamesH5(const fs::path& file) {
  const H5Reader h5(file);  // the file's own errors (missing, not HDF5) come from here
  if (!h5.has(kWallsGroup)) return {};
  // H5Reader addresses datasets only; the wall names are the groups' names.
  std::vector<std::string> names;
  try {
    const H5::H5File f(file.string(), H5F_ACC_RDONLY);
    const H5::Group g = f.openGroup(kWallsGroup);
    for (hsize_t i = 0; i < g.getNumObjs(); ++i) names.push_back(g.getObjnameByIdx(i));
  } catch (const H5::Exception& e) {
    throw InputError(file.string(), kWallsGroup, "cannot list the walls: " + e.getDetailMsg());
  }
  return names;
}

WallSeries readWallSeriesH5(const fs::path& file, const std::string& wall) {
  const H5Reader h5(file);
  const std::string name = file.string();
  const std::string walls = kWallsGroup;
  const std::string group = walls + "/" + wall;
  if (!isWallName(wall))
    throw InputError(name, group, "'" + wall + "' is not a wall name (letters, digits, '_' and '-')");
  const std::string format = h5.attribute("/", "format");
  const std::string redo = "run the micro case again with this build (docs/formats.md)";
  if (!h5.has(group)) {
    const std::string missing = "wall '" + wall + "' not found: ";
    if (h5.has(walls)) {
      std::string have;
      for (const auto& w : wallNamesH5(file)) have += (have.empty() ? "" : ", ") + w;
      throw InputError(name, group, "no wall named '" + wall + "' in this file (its walls: " + have + ")");
    }
    // gabion.micro.scene/1 wrote /series/wall_<i>_force_N by index: say so
    // rather than "no such dataset".
    if (format == "gabion.micro.scene/1" || h5.has("/series/wall_0_force_N"))
      throw InputError(name, group,
                       missing +
                           "the file has the index-based wall layout of gabion.micro.scene/1 "
                           "(/series/wall_<i>_force_N) and no " +
                           walls + " group, which " + kSceneFormat + " writes with one group per wall name; " + redo);
    if (format == kSceneFormat)
      throw InputError(name, group, missing + "the file has no " + walls + " group (the micro case has no walls)");
    throw InputError(name, group,
                     missing + "the file has no " + walls + " group: not a " + kSceneFormat + " result (" +
                         (format.empty() ? std::string("no format attribute") : "format '" + format + "'") + ")");
  }
  if (format.rfind("gabion.micro.scene/", 0) == 0 && format != kSceneFormat)
    throw InputError(name, group,
                     "the file's format is '" + format + "', this build reads " + kSceneFormat + "; " + redo);
  WallSeries s;
  s.source = name + ":" + group;
  std::size_t n = 0;
  bool first = true;
  for (const auto& [field, out] : {std::pair<const char*, std::vector<Vec3>*>{"force_N", &s.force_N},
                                   {"position_m", &s.position_m},
                                   {"displacement_m", &s.displacement_m}}) {
    const std::string ds = group + "/" + field;
    if (!h5.has(ds))
      throw InputError(name, ds,
                       "wall '" + wall + "' has no " + field + " series (a " + kSceneFormat +
                           " wall has force_N, position_m and displacement_m)");
    const auto d = h5.dims(ds);
    if (d.size() != 2 || d[1] != 3) throw InputError(name, ds, "must be an (n, 3) dataset");
    if (!first && d[0] != n)
      throw InputError(name, ds,
                       "has " + std::to_string(d[0]) + " rows, force_N has " + std::to_string(n) +
                           " (the series of a wall share /series/time_s)");
    n = d[0];
    first = false;
    const auto v = h5.read(ds);
    out->reserve(n);
    for (std::size_t i = 0; i < n; ++i) out->emplace_back(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
  }
  return s;
}

Curve readWallCurveH5(const fs::path& file, const std::string& wall, const Vec3& direction,
                      const CurveRequest& request) {
  const double norm = direction.norm();
  if (!(norm > 0.0)) throw InputError(file.string(), "", "wall direction must be a non-zero vector");
  const Vec3 d = direction / norm;
  const WallSeries w = readWallSeriesH5(file, wall);
  Curve c;
  c.source = w.source;
  c.x_name = request.x_name;
  c.y_name = request.y_name;
  for (std::size_t i = 0; i < w.force_N.size(); ++i) {
    c.x.push_back(w.displacement_m[i].dot(d));
    c.y.push_back(-w.force_N[i].dot(d));
  }
  validateCurve(c, request, {});
  return c;
}

void writeCurveCsv(const fs::path& file, const Curve& c) {
  std::ostringstream out;
  out << c.x_name << "," << c.y_name << "\n" << std::setprecision(17);
  for (std::size_t i = 0; i < c.x.size(); ++i) out << c.x[i] << "," << c.y[i] << "\n";
  writeTextAtomic(file, out.str());
}

}  // namespace gabion::bridge
