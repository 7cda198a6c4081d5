#include "app/registry.hpp"

#include "app/hybrid.hpp"
#include "app/pipeline.hpp"
#include "app/resolved.hpp"
#include "fitting/cases.hpp"
#include "macro/cases.hpp"
#include "micro/cases.hpp"

namespace gabion::app {

const std::vector<bridge::CaseKind>& allKinds() {
  static const std::vector<bridge::CaseKind> kinds = [] {
    std::vector<bridge::CaseKind> all;
    for (auto&& list : {micro::caseKinds(), macro::caseKinds(), fitting::caseKinds()})
      all.insert(all.end(), list.begin(), list.end());
    // (macro.impact with "resolve" runs the hybrid structure, which needs both scales)
    for (bridge::CaseKind& k : all)
      if (k.kind == "macro.impact") k = withHybrid(k);
    all.push_back(pipelineKind());
    all.push_back(resolvedKind());
    return all;
  }();
  return kinds;
}

const bridge::CaseKind* findKind(const std::string& kind) {
  for (const auto& k : allKinds())
    if (k.kind == kind) return &k;
  return nullptr;
}

const bridge::CaseKind& checkCase(const bridge::JsonDocument& doc, const std::string& expected_kind) {
  const auto root = doc.root();
  const std::string format = root.string("format");
  if (format != "gabion.case/1") root.fail("format", "expected 'gabion.case/1', got '" + format + "'");
  const std::string kind = root.string("kind");
  if (!expected_kind.empty() && kind != expected_kind)
    root.fail("kind", "expected a '" + expected_kind + "' case, got '" + kind + "'");
  const auto* k = findKind(kind);
  if (k == nullptr) root.fail("kind", "unknown case kind '" + kind + "' (known: " + kindList() + ")");
  k->check(doc);
  if (root.has("description")) root.string("description");
  doc.finish();
  return *k;
}

std::string kindList() {
  std::string out;
  for (const auto& k : allKinds()) out += (out.empty() ? "" : ", ") + k.kind;
  return out.empty() ? "none" : out;
}

}  // namespace gabion::app
