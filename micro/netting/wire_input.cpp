#include "micro/netting/wire_input.hpp"

namespace gabion::micro {

using bridge::JsonReader;
using bridge::Check;

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
    t.fail(issue.at < 0 ? field : field + "/" + std::to_string(issue.at), issue.message);
  }
  return table;
}

bridge::DoubleTwistParams parseDoubleTwist(const JsonReader& r, const std::string& key) {
  bridge::DoubleTwistParams p;
  const auto d = r.optionalObject(key);
  if (!d) return p;
  p.lambda_k = d->number("lambda_k", p.lambda_k, Check::Fraction);
  p.lambda_eps = d->number("lambda_eps", p.lambda_eps, Check::Positive);
  if (p.lambda_eps > 1.0) d->fail("lambda_eps", "must be in (0, 1]");
  p.poisson = d->number("poisson", p.poisson, Check::NonNegative);
  if (p.poisson >= 0.5) d->fail("poisson", "must be in [0, 0.5)");
  return p;
}

}  // namespace gabion::micro
