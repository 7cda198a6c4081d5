#pragma once
/// \file
/// The two case kinds of the macro module: `macro.impact` (one structure,
/// one impact or a list of impacts, full result files) and `macro.sweep` (a
/// grid of impacts run in parallel, a table and design charts).
#include "bridge/run.hpp"
#include "macro/impact.hpp"

namespace gabion::macro {

/// Validates a macro.impact case (InputError on bad input).
void checkImpactCase(const bridge::JsonDocument& doc);
/// Runs a macro.impact case; writes result.h5 and result.xdmf into ctx.outdir.
bridge::RunOutcome runImpactCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx);

/// Validates a macro.sweep case.
void checkSweepCase(const bridge::JsonDocument& doc);
/// Runs a macro.sweep case; writes sweep.csv, result.h5 and the design charts.
bridge::RunOutcome runSweepCase(const bridge::JsonDocument& doc, const bridge::RunContext& ctx);

/// The summary entries of one impact.
nlohmann::json toJson(const ImpactResult& r);

}  // namespace gabion::macro
