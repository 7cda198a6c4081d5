#pragma once
/// \file
/// Reading the wire law from a case: the stress-strain table
/// (`{"strain": [...], "stress_Pa": [...]}`, checked point by point) and the
/// double-twist factors. Used by the netting and by `"law": "wire"` links of
/// a micro.scene (docs/netting.md).
#include "bridge/json_reader.hpp"
#include "bridge/laws/wire.hpp"

namespace gabion::micro {

/// The table at `key` of r, or the published default if r has no such key.
/// A bad point fails naming it, e.g. /netting/wire/stress_strain/strain/3.
bridge::WireStressStrain parseWireTable(const bridge::JsonReader& r, const std::string& key);

/// The double-twist factors at `key` of r (defaults of bridge::DoubleTwistParams
/// for the keys it lacks, or for all if r has no such key), checked against
/// the wire table they scale.
bridge::DoubleTwistParams parseDoubleTwist(const bridge::JsonReader& r, const std::string& key,
                                           const bridge::WireStressStrain& table);

}  // namespace gabion::micro
