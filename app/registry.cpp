#include "app/registry.hpp"

#include "fitting/cases.hpp"
#include "macro/cases.hpp"
#include "micro/cases.hpp"

namespace gabion::app {

const std::vector<bridge::CaseKind>& allKinds() {
  static const std::vector<bridge::CaseKind> kinds = [] {
    std::vector<bridge::CaseKind> all;
    for (auto&& list : {micro::caseKinds(), macro::caseKinds(), fitting::caseKinds()})
      all.insert(all.end(), list.begin(), list.end());
    return all;
  }();
  return kinds;
}

const bridge::CaseKind* findKind(const std::string& kind) {
  for (const auto& k : allKinds())
    if (k.kind == kind) return &k;
  return nullptr;
}

std::string kindList() {
  std::string out;
  for (const auto& k : allKinds()) out += (out.empty() ? "" : ", ") + k.kind;
  return out.empty() ? "none" : out;
}

}  // namespace gabion::app
