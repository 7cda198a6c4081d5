#pragma once
/// \file
/// Reading the parts shared by the fitting cases (`fit`, `fit.micro`): curve
/// sources, optimizer and objective settings. Every key is read through a
/// JsonReader, so a typo or a bad value names the case file and JSON pointer.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bridge/curve.hpp"
#include "bridge/json_reader.hpp"
#include "fitting/curve_model.hpp"
#include "fitting/law_fit.hpp"
#include "fitting/optimizer.hpp"

namespace gabion::fitting {

/// A named wall of a micro.scene result and the direction it is driven in
/// (bridge::readWallCurveH5).
struct WallCurve {
  std::string name;                 ///< the wall's "name" in the micro case (unnamed: "wall_<index>")
  bridge::Vec3 direction{0, 0, 1};  ///< driving direction (non-zero)
};

/// Reads a "wall": {"name", "direction"} object. An "index" key (the layout of
/// gabion.micro.scene/1) is refused with a message that says to name the wall.
WallCurve readWallCurve(const bridge::JsonReader& w);

/// Where one curve comes from (a case's "curves" entry).
struct CurveSource {
  std::filesystem::path file;  ///< resolved against the case file's folder
  enum class Kind { Csv, H5Datasets, H5Wall } kind = Kind::Csv;
  std::string x_dataset, y_dataset;  ///< H5Datasets
  /// The curve's time axis (a law with a rate term needs it): an H5 dataset
  /// (H5Datasets) or a CSV column (Csv); empty: none.
  std::string t_dataset, t_column;
  WallCurve wall;  ///< H5Wall: /series/walls/<name>/...
  bridge::CurveRequest request;
  std::string replicate;            ///< replicate label
  std::optional<double> condition;  ///< normal force (N) or velocity (m/s) when given in the case
  std::string condition_dataset;    ///< H5: dataset holding the condition when not given
  std::string pointer;              ///< JSON pointer of the entry (for messages)
};

/// Defaults of a curve entry for one test (column and dataset names).
struct CurveDefaults {
  std::string x_name, y_name;       ///< CSV columns (name_unit)
  std::string h5_group;             ///< "/curves/axial" etc.
  std::string condition_key;        ///< "normal_force_N", "velocity_m_s" or ""
  bool replicate_per_curve = true;  ///< default label: each curve its own replicate
};

/// Reads one "curves" entry: {"file", "path", "replicate", "x_column", "y_column",
/// "t_column", "x_dataset", "y_dataset", "t_dataset", "wall": {"name", "direction"},
/// <condition key>, "min_points"}.
CurveSource readCurveSource(const bridge::JsonReader& r, const CurveDefaults& d, std::size_t index,
                            const std::filesystem::path& base_dir);
/// Reads the curve, and its time axis where the entry names one (throws
/// InputError naming file, line and column; a time axis of another length
/// than the curve, or not strictly increasing, names its dataset or column).
bridge::Curve loadCurve(const CurveSource& s);
/// The condition of a curve: the case value, else the mean of the H5 dataset.
double curveCondition(const CurveSource& s);

/// Reads "optimizer": {"global", "local", "global_max_evaluations",
/// "local_max_evaluations", "xtol_rel", "ftol_rel", "penalty"} and the case "seed".
OptimizerSettings readOptimizer(const std::optional<bridge::JsonReader>& r, unsigned long seed,
                                const OptimizerSettings& defaults);
/// Reads "objective": {"loss": "soft_l1"|"huber"|"l2", "loss_scale", "grid_points"}.
LossSettings readLoss(const std::optional<bridge::JsonReader>& r, std::size_t& grid_points);
/// Reads {"name": [lower, upper], ...} for the given names (all required).
Bounds readBounds(const bridge::JsonReader& r, const std::vector<std::string>& names);

/// A parameter of a case run inside the objective (fit.micro, fit.macro):
/// its search range and the key paths of the run's case it is written to.
struct CaseParameter {
  Parameter param;
  std::vector<std::string> set;  ///< dotted paths for JsonDocument::applySet
};

/// Reads "parameters": [{"name", "set", "bounds", "scale"}, ...] (at least
/// one): `set` a key path or a list of them (`set_example` shows one in the
/// message), `bounds` [lower, upper], `scale` auto, log or linear. `name` is
/// required when `name_required`, else it defaults to the first key path.
std::vector<CaseParameter> readCaseParameters(const bridge::JsonReader& root, const std::string& set_example,
                                              bool name_required);
/// `base` with each parameter's value written at its keys (full precision).
bridge::JsonDocument withParameters(const bridge::JsonDocument& base, const std::vector<CaseParameter>& params,
                                    const std::vector<double>& values);
/// The middle of every parameter's range (in its search scale).
std::vector<double> midpoint(const std::vector<CaseParameter>& params);
/// True when the key path `set` (dotted) and the JSON pointer `pointer`
/// name the same value or one holds the other: an error at `pointer` of a
/// case that had `set` written comes from it.
bool setPathMatches(const std::string& set, const std::string& pointer);
/// A number as written into a case by withParameters (17 digits).
std::string fullPrecision(double v);

/// The folder relative paths in a case are resolved against.
std::filesystem::path caseDirectory(const bridge::JsonDocument& doc);

}  // namespace gabion::fitting
