#include <freeinit/app_support/stop_signal.h>

#include <atomic>
#include <csignal>

namespace freeinit::app_support {
namespace {

// Written by the handler: a lock-free atomic int is async-signal-safe.
std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

extern "C" void onStopSignal(int sig) {
  int expected = 0;
  g_signal.compare_exchange_strong(expected, sig);  // the first signal is the one reported
}

}  // namespace

Interrupted::Interrupted(int signal)
    : std::runtime_error("interrupted by " + signalName(signal)), signal_(signal) {}

void installStopHandlers() {
  struct sigaction sa = {};
  sa.sa_handler = onStopSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);
  struct sigaction ignore = {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGPIPE, &ignore, nullptr);
}

int stopSignal() { return g_signal.load(std::memory_order_relaxed); }

void throwIfStopRequested() {
  if (const int s = stopSignal()) throw Interrupted(s);
}

void requestStop(int signal) { onStopSignal(signal); }
void clearStopRequest() { g_signal.store(0); }

std::string signalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "signal " + std::to_string(signal);
  }
}

}  // namespace freeinit::app_support
