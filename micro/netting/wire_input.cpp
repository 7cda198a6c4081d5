#include "micro/netting/wire_input.hpp"

namespace gabion::micro {

using bridge::Check;
using bridge::JsonReader;

bridge::WireStressStrain parseWireTable(const JsonReader& r, const std::string& key) {
  if (!r.has(key)) return bridge::defaultWireTable();
  const JsonReader t = r.object(key);
  bridge::WireStressStrain table;
  table.strain = t.numbers("strain");
  table.stress_Pa = t.numbers("stress_Pa");
  if (table.strain.size() != table.stress_Pa.size())
    t.fail("stress_Pa", "expected one stress per strain (" + std::to_string(table.strain.size()) + " strains, " +
                            std::to_string(table.stress_Pa.size()) + " stresses)");
  const bridge::WireTableIssue issue = bridge::checkWireTable(table);
  if (!issue.message.empty()) {
    const std::string field = issue.strain ? "strain" : "stress_Pa";
    if (issue.at < 0) t.fail(field, issue.message);
    t.failElement(field, static_cast<std::size_t>(issue.at), issue.message);
  }
  return table;
}

bridge::DoubleTwistParams parseDoubleTwist(const JsonReader& r, const std::string& key,
                                           const bridge::WireStressStrain& table) {
  bridge::DoubleTwistParams p;
  const auto d = r.optionalObject(key);
  if (d) {
    p.lambda_k = d->number("lambda_k", p.lambda_k, Check::Positive);
    if (p.lambda_k > 1.0) d->fail("lambda_k", "must be in (0, 1]");
    p.lambda_eps = d->number("lambda_eps", p.lambda_eps, Check::Positive);
    if (p.lambda_eps > 1.0) d->fail("lambda_eps", "must be in (0, 1]");
  }
  const std::string issue = bridge::checkDoubleTwist(table, p);
  if (!issue.empty()) r.fail(key, issue);
  return p;
}

}  // namespace gabion::micro
