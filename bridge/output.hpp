#pragma once
/// \file
/// Result files. Every file is written under a temporary name (`NAME.part`) and
/// renamed when complete, so a crash never leaves a truncated file that looks
/// complete, and an earlier complete file is replaced only by a complete one.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace gabion::bridge {

/// Writes `value` (pretty-printed) to `path` atomically.
void writeJsonAtomic(const std::filesystem::path& path, const nlohmann::json& value);
/// Writes `text` to `path` atomically.
void writeTextAtomic(const std::filesystem::path& path, const std::string& text);

/// An HDF5 file being written. Datasets are float64 arrays addressed by path
/// ("/series/time_s"); groups are created on the way. The file appears under
/// its final name only after commit(); a writer destroyed without commit()
/// removes its temporary file. A failed write throws WriteError (a full disk
/// ends the run with exit 1 and a message, not a crash).
class H5Writer {
 public:
  explicit H5Writer(std::filesystem::path final_path);
  ~H5Writer();
  H5Writer(const H5Writer&) = delete;
  H5Writer& operator=(const H5Writer&) = delete;

  /// A 1-D dataset. `unit` is stored as the string attribute "unit".
  void write(const std::string& dataset, const std::vector<double>& values, const std::string& unit = "");
  /// An N-D dataset in row-major (C) order; data.size() must equal the product of dims.
  void write(const std::string& dataset, const std::vector<double>& data, const std::vector<std::size_t>& dims,
             const std::string& unit = "");
  /// Appends one row to a dataset whose first dimension grows (created on the
  /// first call with shape (0, row_dims...), chunked by row): a run streams its
  /// snapshots instead of keeping them in memory. row.size() must equal the
  /// product of row_dims, and row_dims must not change between calls.
  void appendRow(const std::string& dataset, const std::vector<double>& row, const std::vector<std::size_t>& row_dims,
                 const std::string& unit = "");
  /// A 1-D integer dataset.
  void writeInts(const std::string& dataset, const std::vector<long long>& values);
  /// An N-D integer dataset in row-major order.
  void writeInts(const std::string& dataset, const std::vector<long long>& values,
                 const std::vector<std::size_t>& dims);
  /// A string attribute on the root group or on an existing object.
  void attribute(const std::string& object, const std::string& name, const std::string& value);
  /// Reads back rows [first, first + rows) of a dataset this writer wrote
  /// (along its first dimension), as doubles in row-major order: a run copies
  /// the snapshots it streamed into a checkpoint (micro/checkpoint.hpp).
  std::vector<double> readRows(const std::string& dataset, std::size_t first, std::size_t rows);
  /// Closes the file and renames it to its final name.
  void commit();
  const std::filesystem::path& path() const { return final_; }

 private:
  [[noreturn]] void fail(const std::string& what, const std::string& detail);
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::filesystem::path final_, part_;
  bool committed_ = false, failed_ = false;
};

/// True once a writer whose writes failed was destroyed: its HDF5 handle was
/// left open (closing it crashes HDF5 1.10), and the library's clean-up at
/// exit would crash on it. The process must then end with std::_Exit after
/// flushing its streams (app/main.cpp does).
bool hdf5HandlesAbandoned();

/// Read access to an HDF5 file written by Gabion (or any float64 datasets).
/// Errors (missing file, corrupt file, missing dataset) throw InputError naming
/// the file and the dataset.
class H5Reader {
 public:
  explicit H5Reader(const std::filesystem::path& path);
  ~H5Reader();
  H5Reader(const H5Reader&) = delete;
  H5Reader& operator=(const H5Reader&) = delete;
  bool has(const std::string& dataset) const;
  std::vector<std::size_t> dims(const std::string& dataset) const;
  /// The whole dataset flattened in row-major order, converted to double.
  std::vector<double> read(const std::string& dataset) const;
  /// The same, converted to 64-bit integers (exact for an integer dataset).
  std::vector<long long> readInts(const std::string& dataset) const;
  /// A string attribute; empty when absent.
  std::string attribute(const std::string& object, const std::string& name) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string file_;
};

/// One point-cloud attribute for an XDMF file: a time-major HDF5 dataset of
/// shape (times, points, components) or, when `per_time` is false, (points).
struct XdmfField {
  std::string name;      ///< name shown in ParaView
  std::string dataset;   ///< HDF5 dataset path
  int components = 1;    ///< 1 (scalar) or 3 (vector)
  bool per_time = true;  ///< false for constant fields such as radius
};

/// Line segments between the points, shown over them (the links of a
/// netting): for each time, an integer (count, 2) dataset of point indices.
/// Segments that are not in a time's dataset are not drawn at that time.
struct XdmfLines {
  std::string name = "links";
  std::vector<std::string> dataset;  ///< per time (several times may share one)
  std::vector<std::size_t> count;    ///< segments per time
};

/// Writes an XDMF 2 file that lets ParaView open a time series of point
/// clouds stored in `h5_name` (relative to the XDMF file): positions from the
/// (times, points, 3) dataset `positions`, plus `fields`, and `lines` between
/// the points if it has any.
void writeXdmfPoints(const std::filesystem::path& xdmf_path, const std::string& h5_name,
                     const std::vector<double>& times, std::size_t points, const std::string& positions,
                     const std::vector<XdmfField>& fields, const XdmfLines& lines = {});

}  // namespace gabion::bridge
