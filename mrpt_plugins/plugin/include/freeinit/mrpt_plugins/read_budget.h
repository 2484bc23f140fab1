// What reading one rawlog record may allocate. MRPT 2.5.8 deserializes lengths and counts as the
// file states them and allocates before reading the data (a 32-bit string length, the number of
// objects of a sensory frame or action collection, the size of a points map), and its aligned
// allocator returns null instead of throwing: a few corrupt bytes make it allocate gigabytes or
// crash. A ReadBudget, opened by the rawlog reader around each record, gives this thread a total
// it may allocate; the program's allocation functions (alloc_guard.cpp: operator new and MRPT's
// aligned allocator, linked into every app) charge it and throw std::bad_alloc, before
// allocating, for the request that would exceed it. Requests under kLargeRequest are counted but
// never refused (the corrupt counts ask for one large block; MRPT's error handling, which may not
// throw, needs small ones). Programs without them (stock MRPT tools loading the plugin) are
// unguarded; the reader works the same.
#pragma once

#include <cstddef>

namespace freeinit::mrpt_plugins {

class ReadBudget {
 public:
  /// [bytes] requests from this size on are refused when they do not fit.
  static constexpr std::size_t kLargeRequest = std::size_t{64} << 10;

  /// Opens a budget of `bytes` for this thread (replacing any open one until destroyed).
  explicit ReadBudget(std::size_t bytes) noexcept;
  ~ReadBudget();
  ReadBudget(const ReadBudget&) = delete;
  ReadBudget& operator=(const ReadBudget&) = delete;

  /// An allocation was refused: the request [bytes] that did not fit, else 0.
  std::size_t refused() const noexcept;
  /// [bytes] allocated within the budget before the refused request.
  std::size_t chargedBeforeRefusal() const noexcept;
  /// [bytes] allocated within the budget so far.
  std::size_t charged() const noexcept;

  /// For the allocation functions: charges `bytes` to this thread's open budget; false (and the
  /// request is recorded) when a large request does not fit. True when no budget is open.
  static bool charge(std::size_t bytes) noexcept;
  /// Whether a budget is open on this thread, charged by this program's allocation functions, and
  /// `bytes` more fit in it. A reader that trusts a count only this far allocates what the count
  /// asks for at once (charged once) instead of growing by parts as the data arrive (charged
  /// about twice: a growing vector's earlier blocks are charged too).
  static bool fits(std::size_t bytes) noexcept;
  /// Whether this program's allocation functions charge budgets (alloc_guard.cpp is linked in).
  static bool enforced() noexcept;
  /// Called once by the guard at start-up.
  static void markEnforced() noexcept;

 private:
  std::size_t saved_limit_, saved_used_, saved_refused_, saved_used_at_refusal_;
  bool saved_open_;
};

}  // namespace freeinit::mrpt_plugins
