// Stopping cleanly on SIGINT, SIGTERM and SIGHUP. The apps' mains install handlers that only
// record the signal; the long loops (reading a rawlog, receiving a stream, simulating, mapping,
// writing outputs) poll it and stop: throwIfStopRequested() throws Interrupted, which unwinds
// through the output set (output_set.h) and the writers, so that no temporary file is left, and
// runMain() then ends the process by the same signal (exit status 128 + signal in a shell).
// SIGPIPE is ignored: a closed stdout (`freeinit ... | head`) must not kill a run half-way.
#pragma once

#include <stdexcept>
#include <string>

namespace freeinit::app_support {

/// A run stopped by a signal.
class Interrupted : public std::runtime_error {
 public:
  explicit Interrupted(int signal);
  int signal() const { return signal_; }

 private:
  int signal_;
};

/// Installs the handlers (once; idempotent).
void installStopHandlers();
/// The signal that asked the process to stop, or 0.
int stopSignal();
inline bool stopRequested() { return stopSignal() != 0; }
/// Throws Interrupted when a stop was requested.
void throwIfStopRequested();
/// As a signal would: for tests and for code that stops the run itself.
void requestStop(int signal);
/// Forgets a requested stop (tests).
void clearStopRequest();
/// "SIGINT", "SIGTERM", ... ("signal N" otherwise).
std::string signalName(int signal);

}  // namespace freeinit::app_support
