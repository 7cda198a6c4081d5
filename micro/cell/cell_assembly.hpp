#pragma once
/// \file
/// The `micro.cell` case (docs/cell.md): a gabion cell assembled as the
/// paper's. A netting basket held by a rigid formwork is filled by gravity
/// with angular blocks to the mass of the target porosity; the formwork and
/// floor are vibrated, with a plate pressing on the fill, until the
/// porosity inside the cell reaches the target or a time limit passes; the
/// lid is laced on; the formwork is taken away and the cell is left to
/// stand on its rigid base until it is at rest. Each stage is a scene run of
/// its own (OUTDIR/fill, vibration, standing), each starting from the state
/// the last one ended in; the packed cell is saved as OUTDIR/cell.h5.
#include "bridge/run.hpp"

namespace gabion::micro {

bridge::CaseKind cellKind();

}  // namespace gabion::micro
