#include "micro/checkpoint.hpp"

#include <cstring>
#include <numeric>
#include <stdexcept>

#include "bridge/errors.hpp"

namespace gabion::micro {

namespace fs = std::filesystem;

namespace {
constexpr const char* kFormat = "gabion.micro.checkpoint/1";

std::size_t product(const std::vector<std::size_t>& dims) {
  return std::accumulate(dims.begin(), dims.end(), std::size_t{1}, std::multiplies<>());
}

// Lists of dimension lists, flattened as (rank, dims...) for an archive.
std::vector<std::size_t> flatten(const std::vector<std::vector<std::size_t>>& lists) {
  std::vector<std::size_t> out;
  for (const auto& l : lists) {
    out.push_back(l.size());
    out.insert(out.end(), l.begin(), l.end());
  }
  return out;
}

std::vector<std::vector<std::size_t>> unflatten(const std::vector<std::size_t>& flat, std::size_t count) {
  std::vector<std::vector<std::size_t>> out;
  std::size_t at = 0;
  while (at < flat.size() && out.size() < count) {
    const std::size_t rank = flat[at++];
    if (at + rank > flat.size()) break;
    out.emplace_back(flat.begin() + static_cast<std::ptrdiff_t>(at),
                     flat.begin() + static_cast<std::ptrdiff_t>(at + rank));
    at += rank;
  }
  if (out.size() != count || at != flat.size())
    throw std::invalid_argument("checkpoint: the snapshot log's dimensions do not match its datasets");
  return out;
}
}  // namespace

// ---------------------------------------------------------------- SnapshotLog

void SnapshotLog::appendRow(const std::string& dataset, const std::vector<double>& row,
                            const std::vector<std::size_t>& row_dims, const std::string& unit) {
  h5_.appendRow(dataset, row, row_dims, unit);
  for (Rows& r : rows_)
    if (r.name == dataset) {
      ++r.rows;
      return;
    }
  rows_.push_back({dataset, unit, row_dims, 1, 0});
}

void SnapshotLog::writeInts(const std::string& dataset, const std::vector<long long>& values,
                            const std::vector<std::size_t>& dims) {
  h5_.writeInts(dataset, values, dims);
  tables_.push_back({dataset, dims, segments_});
}

void SnapshotLog::seal(const fs::path& file) {
  bridge::H5Writer seg(file);
  for (const Table& t : tables_) {
    if (t.segment != segments_) continue;
    const std::vector<double> v = t.dims.empty() ? std::vector<double>{} : h5_.readRows(t.name, 0, t.dims[0]);
    seg.writeInts(t.name, std::vector<long long>(v.begin(), v.end()), t.dims);
  }
  for (Rows& r : rows_) {
    if (r.rows == r.sealed) continue;
    std::vector<std::size_t> dims{r.rows - r.sealed};
    dims.insert(dims.end(), r.row_dims.begin(), r.row_dims.end());
    seg.write(r.name, h5_.readRows(r.name, r.sealed, r.rows - r.sealed), dims, r.unit);
    r.sealed = r.rows;
  }
  seg.commit();
  ++segments_;
}

void SnapshotLog::replay(const std::function<fs::path(std::size_t)>& segment) {
  for (Rows& r : rows_) r.rows = r.sealed = 0;
  for (std::size_t k = 0; k < segments_; ++k) {
    const fs::path file = segment(k);
    const bridge::H5Reader seg(file);
    for (const Table& t : tables_) {
      if (t.segment != k) continue;
      const std::vector<double> v = seg.read(t.name);
      if (v.size() != product(t.dims)) throw bridge::InputError(file.string(), t.name, "not of its recorded size");
      h5_.writeInts(t.name, std::vector<long long>(v.begin(), v.end()), t.dims);
    }
    for (Rows& r : rows_) {
      if (!seg.has(r.name)) continue;
      const std::vector<std::size_t> dims = seg.dims(r.name);
      const std::vector<double> v = seg.read(r.name);
      const std::size_t width = product(r.row_dims), count = dims.empty() ? 0 : dims[0];
      if (v.size() != count * width) throw bridge::InputError(file.string(), r.name, "not a whole number of rows");
      for (std::size_t i = 0; i < count; ++i) {
        h5_.appendRow(r.name,
                      std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(i * width),
                                          v.begin() + static_cast<std::ptrdiff_t>((i + 1) * width)),
                      r.row_dims, r.unit);
        ++r.rows;
      }
      r.sealed = r.rows;
    }
  }
}

void SnapshotLog::archive(bridge::StateArchive& a) {
  std::vector<std::string> names, units, table_names;
  std::vector<std::vector<std::size_t>> row_dims, table_dims;
  std::vector<std::size_t> rows, table_segment;
  for (const Rows& r : rows_) names.push_back(r.name), units.push_back(r.unit), row_dims.push_back(r.row_dims);
  for (const Rows& r : rows_) rows.push_back(r.sealed);
  for (const Table& t : tables_)
    table_names.push_back(t.name), table_dims.push_back(t.dims), table_segment.push_back(t.segment);
  std::vector<std::size_t> flat_rows = flatten(row_dims), flat_tables = flatten(table_dims);
  a("segments", segments_);
  bridge::StateArchive ra = a.group("rows"), ta = a.group("tables");
  ra("datasets", names), ra("units", units), ra("row_dims", flat_rows), ra("rows", rows);
  ta("datasets", table_names), ta("dims", flat_tables), ta("segment", table_segment);
  if (!a.loading()) return;
  if (units.size() != names.size() || rows.size() != names.size() || table_segment.size() != table_names.size())
    throw std::invalid_argument("checkpoint: the snapshot log's lists are of unequal lengths");
  const auto rd = unflatten(flat_rows, names.size()), td = unflatten(flat_tables, table_names.size());
  rows_.clear();
  tables_.clear();
  for (std::size_t k = 0; k < names.size(); ++k) rows_.push_back({names[k], units[k], rd[k], rows[k], rows[k]});
  for (std::size_t k = 0; k < table_names.size(); ++k) tables_.push_back({table_names[k], td[k], table_segment[k]});
}

// ---------------------------------------------------------------- Checkpoints

Checkpoints::Checkpoints(fs::path dir, double every_s, std::uint64_t identity)
    : dir_(std::move(dir)), every_s_(every_s), identity_(identity) {}

fs::path Checkpoints::segment(std::size_t k) const {
  return dir_ / "snapshots" / (std::to_string(k) + ".h5");
}

bool Checkpoints::due() const {
  return every_s_ > 0.0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - last_).count() >= every_s_;
}

Checkpoints::Found Checkpoints::find() const {
  std::error_code ec;
  if (!fs::is_regular_file(state(), ec)) return Found::None;
  const bridge::H5Reader r(state());
  if (r.attribute("/", "format") != kFormat) return Found::Other;
  return r.attribute("/", "identity") == bridge::hexDigest(identity_) ? Found::Ours : Found::Other;
}

void Checkpoints::save(Engine& engine, SnapshotLog& log, const std::function<void(bridge::StateArchive&)>& loop) {
  fs::create_directories(dir_ / "snapshots");
  log.seal(segment(log.segments()));
  bridge::H5Writer w(state());
  bridge::StateArchive a = bridge::StateArchive::saving(w);
  bridge::StateArchive ea = a.group("engine"), la = a.group("snapshots"), ra = a.group("run");
  engine.archive(ea);
  log.archive(la);
  loop(ra);
  w.attribute("/", "format", kFormat);
  w.attribute("/", "identity", bridge::hexDigest(identity_));
  w.attribute("/", "step", std::to_string(engine.steps()));
  w.attribute("/", "time_s", std::to_string(engine.time()));
  w.commit();
  last_ = std::chrono::steady_clock::now();
  ++saved_;
}

void Checkpoints::load(Engine& engine, SnapshotLog& log, const std::function<void(bridge::StateArchive&)>& loop) {
  const bridge::H5Reader r(state());
  bridge::StateArchive a = bridge::StateArchive::loading(r, state().string());
  bridge::StateArchive ea = a.group("engine"), la = a.group("snapshots"), ra = a.group("run");
  try {
    engine.archive(ea);
    log.archive(la);
    log.replay([this](std::size_t k) { return segment(k); });
    loop(ra);
  } catch (const std::invalid_argument& e) {
    throw bridge::InputError(state().string(), "",
                             std::string(e.what()) + "; remove " + dir_.string() + " to start afresh");
  }
  last_ = std::chrono::steady_clock::now();
}

void Checkpoints::remove() {
  std::error_code ec;
  fs::remove_all(dir_, ec);
}

std::uint64_t runIdentity(const std::string& case_digest, const std::string& label, Engine& engine,
                          const std::vector<double>& plan) {
  std::uint64_t h = bridge::fnv1a(case_digest);
  h = bridge::fnv1a(label, h);
  std::string bits(plan.size() * sizeof(double), '\0');
  if (!plan.empty()) std::memcpy(bits.data(), plan.data(), bits.size());
  h = bridge::fnv1a(bits, h);
  bridge::StateArchive d = bridge::StateArchive::digesting();
  engine.archive(d);
  return bridge::fnv1a(bridge::hexDigest(d.digest()), h);
}

}  // namespace gabion::micro
