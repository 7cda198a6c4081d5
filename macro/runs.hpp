#pragma once
/// \file
/// The case kinds of the macro module: `macro.impact` (one structure, one
/// impact or a list of impacts, full result files), `macro.sweep` (a grid of
/// impacts run in parallel, a table and design charts) and `macro.capacity`
/// (the largest impact energy that meets the acceptance criteria) and
/// `macro.design` (the smallest section that meets them).
#include <memory>
#include <optional>

#include "bridge/run.hpp"
#include "macro/impact.hpp"

namespace gabion::macro {

/// Validates a macro.impact case (InputError on bad input).
void checkImpactCase(const bridge::JsonDocument& doc);
/// What a macro.impact case costs at most (bridge/cost.hpp).
std::optional<bridge::Estimate> estimateImpactCase(const bridge::JsonDocument& doc);
/// Runs a macro.impact case; writes result.h5 and result.xdmf into ctx.outdir.
bridge::RunOutcome runImpactCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx);

/// Validates a macro.sweep case.
void checkSweepCase(const bridge::JsonDocument& doc);
/// What a macro.sweep case costs at most (bridge/cost.hpp).
std::optional<bridge::Estimate> estimateSweepCase(const bridge::JsonDocument& doc);
/// Runs a macro.sweep case; writes sweep.csv, result.h5 and the design charts.
bridge::RunOutcome runSweepCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx);
/// A macro.sweep case's points as rows (bridge/rows.hpp): a row per point.
std::shared_ptr<const bridge::RowPlan> sweepRows(const bridge::JsonDocument& doc);

/// Validates a macro.capacity case.
void checkCapacityCase(const bridge::JsonDocument& doc);
/// What a macro.capacity case costs at most (bridge/cost.hpp).
std::optional<bridge::Estimate> estimateCapacityCase(const bridge::JsonDocument& doc);
/// Runs a macro.capacity case: bisection over the boulder's velocity or mass.
bridge::RunOutcome runCapacityCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx);

/// Validates a macro.design case.
void checkDesignCase(const bridge::JsonDocument& doc);
/// What a macro.design case costs at most (bridge/cost.hpp).
std::optional<bridge::Estimate> estimateDesignCase(const bridge::JsonDocument& doc);
/// A macro.design case's search as rows (bridge/rows.hpp): a row per front
/// material and height (bisection), or per section (exhaustive).
std::shared_ptr<const bridge::RowPlan> designRows(const bridge::JsonDocument& doc);
/// Runs a macro.design case: the smallest section that meets the criteria.
bridge::RunOutcome runDesignCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx);

/// The summary entries of one impact.
nlohmann::json toJson(const ImpactResult& r);

}  // namespace gabion::macro
