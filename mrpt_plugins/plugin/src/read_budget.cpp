#include <freeinit/mrpt_plugins/read_budget.h>

#include <atomic>

namespace freeinit::mrpt_plugins {
namespace {

struct State {
  bool open = false;
  std::size_t limit = 0, used = 0, refused = 0, used_at_refusal = 0;
};
// Initial-exec TLS: no allocation on first use (this is reached from operator new).
thread_local State t_state __attribute__((tls_model("initial-exec")));
std::atomic<bool> g_enforced{false};

}  // namespace

ReadBudget::ReadBudget(std::size_t bytes) noexcept
    : saved_limit_(t_state.limit),
      saved_used_(t_state.used),
      saved_refused_(t_state.refused),
      saved_used_at_refusal_(t_state.used_at_refusal),
      saved_open_(t_state.open) {
  t_state = State{true, bytes, 0, 0, 0};
}

ReadBudget::~ReadBudget() {
  t_state = State{saved_open_, saved_limit_, saved_used_, saved_refused_, saved_used_at_refusal_};
}

std::size_t ReadBudget::refused() const noexcept { return t_state.refused; }
std::size_t ReadBudget::chargedBeforeRefusal() const noexcept { return t_state.used_at_refusal; }
std::size_t ReadBudget::charged() const noexcept { return t_state.used; }

bool ReadBudget::charge(std::size_t bytes) noexcept {
  State& s = t_state;
  if (!s.open) return true;
  // Small requests are counted, never refused: MRPT builds its error messages (with a backtrace)
  // inside what(), which may not throw, so a refusal there would terminate the program.
  if (bytes >= kLargeRequest && (bytes > s.limit || s.used > s.limit - bytes)) {
    if (s.refused == 0) {
      s.refused = bytes;
      s.used_at_refusal = s.used;
    }
    return false;
  }
  s.used += bytes;
  return true;
}

bool ReadBudget::fits(std::size_t bytes) noexcept {
  const State& s = t_state;
  return s.open && enforced() && s.refused == 0 && bytes <= s.limit && s.used <= s.limit - bytes;
}

bool ReadBudget::enforced() noexcept { return g_enforced.load(std::memory_order_relaxed); }
void ReadBudget::markEnforced() noexcept { g_enforced.store(true, std::memory_order_relaxed); }

}  // namespace freeinit::mrpt_plugins
