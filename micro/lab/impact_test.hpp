#pragma once
/// \file
/// `micro.uci`, the unconfined impact test of a cell (docs/lab.md): the cell
/// stands on a rigid base, a spherical boulder (500 mm, 2,600 kg/m3 by
/// default) strikes its top face at a set velocity (the paper's 8-30 m/s).
/// The force on the boulder and on the base against time, the boulder's
/// penetration, the contact's duration, the rebound and the broken wires.
#include "bridge/run.hpp"

namespace gabion::micro::lab {

bridge::CaseKind unconfinedImpactKind();

}  // namespace gabion::micro::lab
