#pragma once
/// \file
/// Stopping a long run cleanly on SIGINT (Ctrl-C) or SIGTERM (a scheduler's
/// kill): the first signal sets a flag that the long loops poll (a fine-DEM
/// step loop, a sweep's points, the pipeline's stages); they stop, write
/// what they have, and the run ends with status "interrupted". A second
/// signal ends the process at once.
namespace gabion::bridge {

/// Installs the handlers (the `gabion` command does, once).
void installInterruptHandlers();

/// The signal that asked the run to stop (SIGINT, SIGTERM), or 0.
int interruptSignal();

inline bool interrupted() {
  return interruptSignal() != 0;
}

/// Sets the flag as a signal would (tests; or a caller that must stop).
void requestInterrupt(int signal);

/// "SIGINT", "SIGTERM" or "signal N".
const char* signalName(int signal);

}  // namespace gabion::bridge
