#include "bridge/interrupt.hpp"

#include <csignal>

namespace gabion::bridge {

namespace {

volatile std::sig_atomic_t g_signal = 0;

extern "C" void onInterrupt(int signal) {
  g_signal = signal;
  std::signal(signal, SIG_DFL);  // a second one ends the process
}

}  // namespace

void installInterruptHandlers() {
  std::signal(SIGINT, onInterrupt);
  std::signal(SIGTERM, onInterrupt);
  // A write past the file-size limit (ulimit -f) fails with EFBIG and ends
  // the run with a message naming the file (bridge::WriteError), instead of
  // killing the process in the middle of its files.
  std::signal(SIGXFSZ, SIG_IGN);
}

int interruptSignal() {
  return g_signal;
}

void requestInterrupt(int signal) {
  g_signal = signal;
}

const char* signalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "a signal";
  }
}

}  // namespace gabion::bridge
