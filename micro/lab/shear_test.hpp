#pragma once
/// \file
/// `micro.shear`, the interface shear test (docs/lab.md): one cell on
/// another, the lower held in a box, a servo plate holding the normal load on
/// the upper one, which a plate pushes sideways at a set speed. The
/// tangential force against displacement, and the inter-cell friction
/// coefficient and tangential stiffness it implies.
#include "bridge/run.hpp"

namespace gabion::micro::lab {

bridge::CaseKind interfaceShearKind();

}  // namespace gabion::micro::lab
