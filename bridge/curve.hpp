#pragma once
/// \file
/// Test curves (force against displacement and the like) read from lab CSV
/// files or from HDF5 result files, with validation that names the file, the
/// line and the column of the first bad value. Formats: docs/fitting.md.
#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bridge/json_reader.hpp"

namespace gabion::bridge {

/// One measured or simulated curve y(x), in the order it was recorded (the
/// loading path: x may reverse for loading/unloading curves).
struct Curve {
  std::string source;        ///< file (and dataset or columns) it came from
  std::string x_name;        ///< column/dataset name with its SI unit suffix, e.g. "displacement_m"
  std::string y_name;        ///< e.g. "force_N"
  std::vector<double> x, y;  ///< same length, finite
  /// The time of each point (s), strictly increasing; empty when the source
  /// gives none. A law with a rate term reads the rate dx/dt from it.
  std::vector<double> t = {};
  std::size_t size() const { return x.size(); }
};

/// How the rows of a curve must be ordered.
enum class CurvePath {
  Monotonic,  ///< x non-decreasing (a loading curve); anything else is "unsorted"
  Cyclic      ///< x may reverse (loading/unloading); the row order is the path
};

/// What a reader expects of a curve file.
struct CurveRequest {
  std::string x_name = "displacement_m";  ///< required column / dataset name (its suffix is the unit)
  std::string y_name = "force_N";
  CurvePath path = CurvePath::Monotonic;
  std::size_t min_points = 5;  ///< fewer rows than this is an error
};

/// A CSV table of numbers: the columns asked for, by name, one value per data
/// row, and the file line of every row (for messages).
struct CsvTable {
  std::string source;                                  ///< the file
  std::vector<std::string> header;                     ///< every column's name, in order
  std::size_t header_line = 0;                         ///< line of the header
  std::map<std::string, std::vector<double>> columns;  ///< the columns read (required, and optional ones present)
  std::vector<std::size_t> lines;                      ///< file line of each row
  std::size_t rows() const { return lines.size(); }
  /// 1-based column of `name` (0: absent).
  std::size_t column(const std::string& name) const;
  /// "line L, column C (name)" of a cell, for an InputError.
  std::string where(std::size_t row, const std::string& name) const;
};

/// Reads a CSV table: a header line with the column names (each ending in its
/// SI unit), then one row of numbers per line; blank lines and lines starting
/// with '#' are skipped. Reads the `required` columns and those of
/// `optional` that the header has; other columns are ignored. Throws
/// InputError (file, "line L, column C (name)", message) for a missing or
/// empty file, a missing column (or one of the right name and another unit,
/// `velocity_km_h` for `velocity_m_s`), a row with the wrong number of cells,
/// and a non-numeric or non-finite cell in a column read.
CsvTable readCsvTable(const std::filesystem::path& file, const std::vector<std::string>& required,
                      const std::vector<std::string>& optional = {});

/// Reads a CSV curve (readCsvTable): a header line with the column names (each ending in its SI
/// unit, e.g. `displacement_m,force_N`; other columns are allowed and ignored,
/// except `time_s`, which must then increase strictly), then one row of numbers
/// per line. Blank lines and lines starting with '#' are skipped.
/// Throws InputError (file, "line L, column C (name)", message) for: a missing or
/// empty file, a missing column, a column with the right name but another unit
/// (`displacement_mm`), a row with the wrong number of cells, a non-numeric or
/// non-finite cell, an unsorted x column (Monotonic) or time_s, fewer than
/// `min_points` rows, or an x column without any spread.
Curve readCurveCsv(const std::filesystem::path& file, const CurveRequest& request);

/// Reads a curve from two 1-D datasets of an HDF5 file (e.g. `/curves/axial/displacement_m`
/// and `/curves/axial/force_N`), with the same checks as readCurveCsv (the "line"
/// named in errors is the 1-based index in the dataset).
Curve readCurveH5(const std::filesystem::path& file, const std::string& x_dataset, const std::string& y_dataset,
                  const CurveRequest& request);

/// The series of one named wall of a micro.scene result (`gabion.micro.scene/2`),
/// one vector per series time.
struct WallSeries {
  std::string source;                ///< "file:/series/walls/<name>" (for messages)
  std::vector<Vec3> force_N;         ///< force the bodies exert on the wall (N)
  std::vector<Vec3> position_m;      ///< the wall's point when that force was evaluated (m)
  std::vector<Vec3> displacement_m;  ///< position_m minus the initial point (m)
};

/// True for a wall name micro.scene accepts (it names an HDF5 group): not empty,
/// letters, digits, '_' and '-' only.
bool isWallName(const std::string& name);

/// Reads `/series/walls/<wall>/{force_N, position_m, displacement_m}`, each (n, 3),
/// of a micro.scene result. Throws InputError naming the file and the wall when
/// the wall is not in the file (the message lists the walls that are), when the
/// file has the index-based layout of `gabion.micro.scene/1`
/// (`/series/wall_<i>_force_N`, refused: run the micro case again), when its
/// `format` attribute names another micro.scene version, or when a dataset is
/// missing or not (n, 3) with the same n as the others. docs/formats.md.
WallSeries readWallSeriesH5(const std::filesystem::path& file, const std::string& wall);

/// The names of the walls of a micro.scene result (the groups under `/series/walls`,
/// sorted by name); empty when the file has none.
std::vector<std::string> wallNamesH5(const std::filesystem::path& file);

/// The force-displacement curve of the wall named `wall` (readWallSeriesH5):
/// displacement_m = (p(t) - p(0)) . d and force_N = -F(t) . d, with `direction` the
/// unit vector d along which the wall is driven and F the force the bodies exert on
/// the wall, so that a wall pressing into a packing gives a positive curve.
Curve readWallCurveH5(const std::filesystem::path& file, const std::string& wall, const Vec3& direction,
                      const CurveRequest& request);

/// Validates x/y of a curve (finite, order, length, spread); errors name c.source and
/// the line of the bad point, taken from `lines` (one per point; empty: 1-based index),
/// and the column numbers of x and y. Used by the readers and for curves built in memory.
void validateCurve(const Curve& c, const CurveRequest& request, const std::vector<std::size_t>& lines = {},
                   std::size_t x_column = 1, std::size_t y_column = 2);

/// Writes a curve as CSV with the header `x_name,y_name` (atomically), full precision.
void writeCurveCsv(const std::filesystem::path& file, const Curve& c);

}  // namespace gabion::bridge
