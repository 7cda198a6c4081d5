#include "bridge/output.hpp"

#include <H5Cpp.h>

#include <atomic>
#include <fstream>
#include <iomanip>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "bridge/errors.hpp"
#include "bridge/manifest.hpp"

namespace gabion::bridge {

namespace fs = std::filesystem;

namespace {

fs::path partPath(const fs::path& p) {
  return fs::path(p.string() + ".part");
}

void renameInto(const fs::path& part, const fs::path& final_path) {
  std::error_code ec;
  fs::rename(part, final_path, ec);
  if (ec) throw WriteError(final_path.string(), "cannot rename " + part.string() + " to it: " + ec.message());
  noteWritten(final_path);
}

// Creates every missing group of "/a/b/dataset" and returns the parent path.
void ensureGroups(H5::H5File& file, const std::string& dataset) {
  std::size_t pos = 1;
  while ((pos = dataset.find('/', pos)) != std::string::npos) {
    const std::string group = dataset.substr(0, pos);
    if (!file.nameExists(group)) file.createGroup(group);
    ++pos;
  }
}

// HDF5 prints nothing (its errors become WriteError/InputError messages),
// and does not close open files at exit: a writer whose writes failed
// leaves its file handle open on purpose (H5Writer::~H5Writer), and closing
// such a file crashes inside the library.
struct QuietHdf5 {
  QuietHdf5() {
    H5dont_atexit();
    H5::Exception::dontPrint();
  }
};
const QuietHdf5 kQuiet;

}  // namespace

namespace {
// Writes through `emit` into PATH.part, then renames it to PATH; on failure
// the part file is removed and PATH is left as it was.
template <class Emit>
void writeAtomic(const fs::path& path, Emit emit) {
  const fs::path part = partPath(path);
  {
    std::ofstream out(part, std::ios::binary | std::ios::trunc);
    if (!out) throw WriteError(part.string(), "cannot create the file");
    emit(out);
    out.flush();
    out.close();
    if (!out) {
      std::error_code ec;
      fs::remove(part, ec);
      throw WriteError(path.string(), "the write failed; the earlier file, if any, is kept");
    }
  }
  renameInto(part, path);
}
}  // namespace

void writeTextAtomic(const fs::path& path, const std::string& text) {
  writeAtomic(path, [&](std::ostream& out) { out << text; });
}

// Streamed: a summary that embeds a large case is never held as one string.
void writeJsonAtomic(const fs::path& path, const nlohmann::json& value) {
  writeAtomic(path, [&](std::ostream& out) { out << std::setw(2) << value << "\n"; });
}

// ---------------------------------------------------------------- H5Writer

struct H5Writer::Impl {
  H5::H5File file;
};

H5Writer::H5Writer(fs::path final_path) : final_(std::move(final_path)), part_(partPath(final_)) {
  try {
    impl_ = std::make_unique<Impl>(Impl{H5::H5File(part_.string(), H5F_ACC_TRUNC)});
  } catch (const H5::Exception& e) {
    throw WriteError(part_.string(), "cannot create the HDF5 file: " + e.getDetailMsg());
  }
}

namespace {
std::atomic<bool> abandoned{false};
}

bool hdf5HandlesAbandoned() {
  return abandoned.load();
}

H5Writer::~H5Writer() {
  if (committed_) return;
  // A file whose writes failed (a full disk) cannot be closed: HDF5 1.10
  // crashes flushing its metadata. Its handle is left open (the process is
  // ending on the error) and the file is unlinked, which frees its space.
  if (failed_) {
    (void)impl_.release();
    abandoned = true;
  }
  impl_.reset();
  std::error_code ec;
  fs::remove(part_, ec);
}

void H5Writer::fail(const std::string& what, const std::string& detail) {
  failed_ = true;
  throw WriteError(final_.string(), what + ": " + detail);
}

void H5Writer::write(const std::string& dataset, const std::vector<double>& values, const std::string& unit) {
  write(dataset, values, {values.size()}, unit);
}

void H5Writer::write(const std::string& dataset, const std::vector<double>& data, const std::vector<std::size_t>& dims,
                     const std::string& unit) {
  const std::size_t n = std::accumulate(dims.begin(), dims.end(), std::size_t{1}, std::multiplies<>());
  if (n != data.size()) throw std::logic_error("H5Writer: " + dataset + ": data size does not match dims");
  try {
    ensureGroups(impl_->file, dataset);
    std::vector<hsize_t> hd(dims.begin(), dims.end());
    H5::DataSpace space(static_cast<int>(hd.size()), hd.data());
    H5::DataSet ds = impl_->file.createDataSet(dataset, H5::PredType::NATIVE_DOUBLE, space);
    if (n > 0) ds.write(data.data(), H5::PredType::NATIVE_DOUBLE);
    if (!unit.empty()) {
      H5::StrType st(H5::PredType::C_S1, unit.size());
      H5::Attribute a = ds.createAttribute("unit", st, H5::DataSpace(H5S_SCALAR));
      a.write(st, unit);
    }
    ds.close();
  } catch (const H5::Exception& e) {
    fail("dataset " + dataset, e.getDetailMsg());
  }
}

void H5Writer::appendRow(const std::string& dataset, const std::vector<double>& row,
                         const std::vector<std::size_t>& row_dims, const std::string& unit) {
  const std::size_t n = std::accumulate(row_dims.begin(), row_dims.end(), std::size_t{1}, std::multiplies<>());
  if (n != row.size()) throw std::logic_error("H5Writer: " + dataset + ": row size does not match row_dims");
  try {
    const int rank = static_cast<int>(row_dims.size()) + 1;
    std::vector<hsize_t> one(static_cast<std::size_t>(rank), 1);
    for (std::size_t d = 0; d < row_dims.size(); ++d) one[d + 1] = std::max<hsize_t>(1, row_dims[d]);
    H5::DataSet ds;
    ensureGroups(impl_->file, dataset);
    if (!impl_->file.nameExists(dataset)) {
      std::vector<hsize_t> start(one), max_dims(one);
      start[0] = 0;
      for (std::size_t d = 0; d < row_dims.size(); ++d) start[d + 1] = row_dims[d];
      max_dims[0] = H5S_UNLIMITED;
      for (std::size_t d = 0; d < row_dims.size(); ++d) max_dims[d + 1] = row_dims[d];
      H5::DataSpace space(rank, start.data(), max_dims.data());
      H5::DSetCreatPropList plist;
      plist.setChunk(rank, one.data());  // one row per chunk
      ds = impl_->file.createDataSet(dataset, H5::PredType::NATIVE_DOUBLE, space, plist);
      if (!unit.empty()) {
        H5::StrType st(H5::PredType::C_S1, unit.size());
        ds.createAttribute("unit", st, H5::DataSpace(H5S_SCALAR)).write(st, unit);
      }
    } else {
      ds = impl_->file.openDataSet(dataset);
    }
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    ds.getSpace().getSimpleExtentDims(dims.data());
    const hsize_t at = dims[0];
    dims[0] = at + 1;
    ds.extend(dims.data());
    if (n == 0) return;
    H5::DataSpace file_space = ds.getSpace();
    std::vector<hsize_t> offset(static_cast<std::size_t>(rank), 0), count(dims);
    offset[0] = at;
    count[0] = 1;
    file_space.selectHyperslab(H5S_SELECT_SET, count.data(), offset.data());
    H5::DataSpace mem_space(rank, count.data());
    ds.write(row.data(), H5::PredType::NATIVE_DOUBLE, mem_space, file_space);
    ds.close();  // (here, so that a failed flush throws instead of printing from the destructor)
  } catch (const H5::Exception& e) {
    fail("dataset " + dataset, e.getDetailMsg());
  }
}

void H5Writer::writeInts(const std::string& dataset, const std::vector<long long>& values) {
  writeInts(dataset, values, {values.size()});
}

void H5Writer::writeInts(const std::string& dataset, const std::vector<long long>& values,
                         const std::vector<std::size_t>& dims) {
  std::size_t total = 1;
  for (const std::size_t d : dims) total *= d;
  if (total != values.size())
    throw std::logic_error("H5Writer::writeInts " + dataset + ": the data do not have the given dimensions");
  try {
    ensureGroups(impl_->file, dataset);
    const std::vector<hsize_t> d(dims.begin(), dims.end());
    H5::DataSpace space(static_cast<int>(d.size()), d.data());
    H5::DataSet ds = impl_->file.createDataSet(dataset, H5::PredType::NATIVE_LLONG, space);
    if (!values.empty()) ds.write(values.data(), H5::PredType::NATIVE_LLONG);
    ds.close();
  } catch (const H5::Exception& e) {
    fail("dataset " + dataset, e.getDetailMsg());
  }
}

void H5Writer::attribute(const std::string& object, const std::string& name, const std::string& value) {
  try {
    H5::StrType st(H5::PredType::C_S1, std::max<std::size_t>(1, value.size()));
    if (object.empty() || object == "/") {
      H5::Group g = impl_->file.openGroup("/");
      g.createAttribute(name, st, H5::DataSpace(H5S_SCALAR)).write(st, value);
    } else {
      if (impl_->file.childObjType(object) == H5O_TYPE_GROUP) {
        impl_->file.openGroup(object).createAttribute(name, st, H5::DataSpace(H5S_SCALAR)).write(st, value);
      } else {
        impl_->file.openDataSet(object).createAttribute(name, st, H5::DataSpace(H5S_SCALAR)).write(st, value);
      }
    }
  } catch (const H5::Exception& e) {
    fail("attribute " + object + "@" + name, e.getDetailMsg());
  }
}

std::vector<double> H5Writer::readRows(const std::string& dataset, std::size_t first, std::size_t rows) {
  try {
    H5::DataSet ds = impl_->file.openDataSet(dataset);
    H5::DataSpace file_space = ds.getSpace();
    const int rank = file_space.getSimpleExtentNdims();
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    file_space.getSimpleExtentDims(dims.data());
    if (rank == 0 || first + rows > dims[0])
      throw std::logic_error("H5Writer::readRows " + dataset + ": rows beyond the dataset");
    std::vector<hsize_t> offset(static_cast<std::size_t>(rank), 0), count(dims);
    offset[0] = first;
    count[0] = rows;
    const std::size_t n = std::accumulate(count.begin(), count.end(), std::size_t{1}, std::multiplies<>());
    std::vector<double> out(n);
    if (n == 0) return out;
    file_space.selectHyperslab(H5S_SELECT_SET, count.data(), offset.data());
    H5::DataSpace mem_space(rank, count.data());
    ds.read(out.data(), H5::PredType::NATIVE_DOUBLE, mem_space, file_space);
    return out;
  } catch (const H5::Exception& e) {
    fail("reading back dataset " + dataset, e.getDetailMsg());
  }
}

void H5Writer::commit() {
  if (committed_) return;
  try {
    impl_->file.close();
  } catch (const H5::Exception& e) {
    fail("closing the file", e.getDetailMsg());
  }
  renameInto(part_, final_);
  committed_ = true;
}

// ---------------------------------------------------------------- H5Reader

struct H5Reader::Impl {
  H5::H5File file;
};

H5Reader::H5Reader(const fs::path& path) : file_(path.string()) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(file_, "", "file does not exist");
  try {
    if (!H5::H5File::isHdf5(file_)) throw InputError(file_, "", "not an HDF5 file (corrupt or wrong format)");
    impl_ = std::make_unique<Impl>(Impl{H5::H5File(file_, H5F_ACC_RDONLY)});
  } catch (const H5::Exception& e) {
    throw InputError(file_, "", "cannot open HDF5 file: " + e.getDetailMsg());
  }
}

H5Reader::~H5Reader() = default;

bool H5Reader::has(const std::string& dataset) const {
  try {
    // nameExists fails on intermediate groups that do not exist: walk them.
    std::size_t pos = 1;
    while ((pos = dataset.find('/', pos)) != std::string::npos) {
      if (!impl_->file.nameExists(dataset.substr(0, pos))) return false;
      ++pos;
    }
    return impl_->file.nameExists(dataset);
  } catch (const H5::Exception&) {
    return false;
  }
}

std::vector<std::size_t> H5Reader::dims(const std::string& dataset) const {
  if (!has(dataset)) throw InputError(file_, dataset, "no such dataset");
  try {
    H5::DataSpace space = impl_->file.openDataSet(dataset).getSpace();
    std::vector<hsize_t> d(static_cast<std::size_t>(space.getSimpleExtentNdims()));
    space.getSimpleExtentDims(d.data());
    return {d.begin(), d.end()};
  } catch (const H5::Exception& e) {
    throw InputError(file_, dataset, "cannot read dataset: " + e.getDetailMsg());
  }
}

std::vector<double> H5Reader::read(const std::string& dataset) const {
  const auto d = dims(dataset);
  const std::size_t n = std::accumulate(d.begin(), d.end(), std::size_t{1}, std::multiplies<>());
  std::vector<double> out(n);
  try {
    if (n > 0) impl_->file.openDataSet(dataset).read(out.data(), H5::PredType::NATIVE_DOUBLE);
  } catch (const H5::Exception& e) {
    throw InputError(file_, dataset, "cannot read dataset (corrupt or not numeric): " + e.getDetailMsg());
  }
  return out;
}

std::vector<long long> H5Reader::readInts(const std::string& dataset) const {
  const auto d = dims(dataset);
  const std::size_t n = std::accumulate(d.begin(), d.end(), std::size_t{1}, std::multiplies<>());
  std::vector<long long> out(n);
  try {
    if (n > 0) impl_->file.openDataSet(dataset).read(out.data(), H5::PredType::NATIVE_LLONG);
  } catch (const H5::Exception& e) {
    throw InputError(file_, dataset, "cannot read dataset (corrupt or not numeric): " + e.getDetailMsg());
  }
  return out;
}

std::string H5Reader::attribute(const std::string& object, const std::string& name) const {
  try {
    H5::Attribute a;
    if (object.empty() || object == "/") {
      H5::Group g = impl_->file.openGroup("/");
      if (!g.attrExists(name)) return "";
      a = g.openAttribute(name);
    } else {
      if (!has(object)) return "";
      H5::DataSet ds = impl_->file.openDataSet(object);
      if (!ds.attrExists(name)) return "";
      a = ds.openAttribute(name);
    }
    std::string value;
    a.read(a.getStrType(), value);
    return value;
  } catch (const H5::Exception& e) {
    throw InputError(file_, object + "@" + name, "cannot read attribute: " + e.getDetailMsg());
  }
}

// ---------------------------------------------------------------- XDMF

void writeXdmfPoints(const fs::path& xdmf_path, const std::string& h5_name, const std::vector<double>& times,
                     std::size_t points, const std::string& positions, const std::vector<XdmfField>& fields,
                     const XdmfLines& lines) {
  std::ostringstream x;
  x.precision(17);
  const std::size_t nt = times.size();
  const bool with_lines = !lines.dataset.empty();
  if (with_lines && (lines.dataset.size() != nt || lines.count.size() != nt))
    throw std::logic_error("writeXdmfPoints: one line dataset and count per time are needed");
  x << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"2.0\">\n <Domain>\n"
    << "  <Grid Name=\"bodies\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  auto slab = [&](std::size_t t, int comps, const std::string& ds) {
    std::ostringstream s;
    s << "     <DataItem ItemType=\"HyperSlab\" Dimensions=\"" << points << " " << comps << "\">\n"
      << "      <DataItem Dimensions=\"3 3\" Format=\"XML\">" << t << " 0 0 1 1 1 1 " << points << " " << comps
      << "</DataItem>\n"
      << "      <DataItem Dimensions=\"" << nt << " " << points << " " << comps
      << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5_name << ":" << ds << "</DataItem>\n"
      << "     </DataItem>\n";
    return s.str();
  };
  for (std::size_t t = 0; t < nt; ++t) {
    // With lines, each time is a spatial collection of the points and the
    // lines between them (same geometry); ParaView shows both.
    if (with_lines)
      x << "   <Grid Name=\"t" << t << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
        << "    <Time Value=\"" << times[t] << "\"/>\n";
    x << "   <Grid Name=\"" << (with_lines ? "points" : "t" + std::to_string(t)) << "\" GridType=\"Uniform\">\n";
    if (!with_lines) x << "    <Time Value=\"" << times[t] << "\"/>\n";
    x << "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << points << "\"/>\n"
      << "    <Geometry GeometryType=\"XYZ\">\n"
      << slab(t, 3, positions) << "    </Geometry>\n";
    for (const auto& f : fields) {
      x << "    <Attribute Name=\"" << f.name << "\" AttributeType=\"" << (f.components == 3 ? "Vector" : "Scalar")
        << "\" Center=\"Node\">\n";
      if (f.per_time) {
        // A (times, points) scalar dataset is addressed as (times, points, 1).
        x << slab(t, f.components, f.dataset);
      } else {
        x << "     <DataItem Dimensions=\"" << points << (f.components == 3 ? " 3" : "")
          << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5_name << ":" << f.dataset
          << "</DataItem>\n";
      }
      x << "    </Attribute>\n";
    }
    x << "   </Grid>\n";
    if (!with_lines) continue;
    x << "   <Grid Name=\"" << lines.name << "\" GridType=\"Uniform\">\n"
      << "    <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\"" << lines.count[t]
      << "\">\n"
      << "     <DataItem Dimensions=\"" << lines.count[t] << " 2\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">"
      << h5_name << ":" << lines.dataset[t] << "</DataItem>\n"
      << "    </Topology>\n"
      << "    <Geometry GeometryType=\"XYZ\">\n"
      << slab(t, 3, positions) << "    </Geometry>\n"
      << "   </Grid>\n"
      << "   </Grid>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  writeTextAtomic(xdmf_path, x.str());
}

}  // namespace gabion::bridge
