#pragma once
/// \file
/// Kept for the includes that still name it: the damping laws (Cundall's
/// local damping and the viscous normal dashpot) live in contact_damping.hpp.
#include "bridge/laws/contact_damping.hpp"
