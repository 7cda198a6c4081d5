#pragma once
/// \file
/// The `micro.netting_tensile` case kind: a flat sheet of netting, the nodes
/// of one short edge clamped, those of the opposite edge pulled at a set
/// speed along the twists until the sheet tears (docs/netting.md).
#include "bridge/run.hpp"

namespace gabion::micro {

/// The kind (check and run), for micro::caseKinds().
bridge::CaseKind nettingTensileKind();

}  // namespace gabion::micro
