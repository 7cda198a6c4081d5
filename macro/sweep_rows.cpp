#include "macro/sweep_rows.hpp"

#include <fstream>
#include <iterator>
#include <string>

#include "bridge/errors.hpp"
#include "bridge/manifest.hpp"

namespace gabion::macro {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// What a row keeps of an impact: what the sweep's table and summary show.
json toRow(std::size_t index, const ImpactResult& r) {
  json j = {{"index", index}, {"ok", r.ok}};
  if (!r.ok) {
    j["message"] = r.message;
    return j;
  }
  j["outcome"] = static_cast<int>(r.outcome);
  j["peak_force_N"] = r.peak_force_N;
  j["max_penetration_m"] = r.max_penetration_m;
  j["contact_duration_s"] = r.contact_duration_s;
  j["rebound_velocity_m_s"] = r.rebound_velocity_m_s;
  j["max_back_face_displacement_m"] = r.max_back_face_displacement_m;
  j["plastic_J"] = r.plastic_J;
  j["friction_J"] = r.friction_J;
  j["balance_rel_error"] = r.balance_rel_error;
  return j;
}

ImpactResult fromRow(const json& j) {
  ImpactResult r;
  r.ok = j.at("ok").get<bool>();
  if (!r.ok) {
    r.message = j.at("message").get<std::string>();
    return r;
  }
  r.outcome = static_cast<Outcome>(j.at("outcome").get<int>());
  r.peak_force_N = j.at("peak_force_N").get<double>();
  r.max_penetration_m = j.at("max_penetration_m").get<double>();
  r.contact_duration_s = j.at("contact_duration_s").get<double>();
  r.rebound_velocity_m_s = j.at("rebound_velocity_m_s").get<double>();
  r.max_back_face_displacement_m = j.at("max_back_face_displacement_m").get<double>();
  r.plastic_J = j.at("plastic_J").get<double>();
  r.friction_J = j.at("friction_J").get<double>();
  r.balance_rel_error = j.at("balance_rel_error").get<double>();
  return r;
}

}  // namespace

SweepRows::SweepRows(fs::path file, const json& case_value, std::size_t points) : file_(std::move(file)) {
  json c = case_value;
  c.erase("description");
  const json header = {{"format", "gabion.sweep_rows/1"}, {"case", c}, {"points", points}};
  std::error_code ec;
  if (fs::exists(file_, ec)) {
    std::ifstream in(file_, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::size_t pos = 0, kept = 0;
    bool same = false;
    std::map<std::size_t, ImpactResult> rows;
    for (std::size_t line = 0; pos < text.size(); ++line) {
      const std::size_t end = text.find('\n', pos);
      if (end == std::string::npos) break;  // (a torn last line: cut off below)
      try {
        const json j = json::parse(text.substr(pos, end - pos));
        if (line == 0) {
          same = j == header;
          if (!same) break;
        } else {
          const auto index = j.at("index").get<std::size_t>();
          if (index < points) rows[index] = fromRow(j);
        }
      } catch (const std::exception&) {
        break;  // (a damaged line: the rows after it are run again)
      }
      pos = end + 1;
      kept = pos;
    }
    if (same) {
      if (kept < text.size()) fs::resize_file(file_, kept);
      done_ = std::move(rows);
      bridge::noteWritten(file_);
      return;
    }
  }
  std::ofstream out(file_, std::ios::trunc);
  out << header.dump() << "\n";
  out.close();
  if (!out) throw bridge::WriteError(file_.string(), "the sweep's row log could not be started");
  bridge::noteWritten(file_);
}

void SweepRows::append(std::size_t index, const ImpactResult& r) {
  const std::string line = toRow(index, r).dump() + "\n";
  const std::lock_guard<std::mutex> lock(mutex_);
  // Appended and closed at once: a killed run loses at most the row being written.
  std::ofstream out(file_, std::ios::app);
  out << line;
  out.close();
  if (!out)
    throw bridge::WriteError(file_.string(), "the row of point " + std::to_string(index) + " could not be written");
}

}  // namespace gabion::macro
