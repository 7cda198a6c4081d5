#pragma once
/// \file
/// The compression tests of a cell (docs/lab.md): `micro.cc`, confined
/// compression between six rigid walls (the axial curve, the four lateral
/// reactions and the lateral reaction coefficient; the F_lim contact cap and
/// unloading-reloading cycles as options), and `micro.uc`, unconfined
/// compression between two plates with the netting alone confining (the
/// axial curve and its sudden force drops).
#include "bridge/run.hpp"

namespace gabion::micro::lab {

bridge::CaseKind confinedCompressionKind();
bridge::CaseKind unconfinedCompressionKind();

}  // namespace gabion::micro::lab
