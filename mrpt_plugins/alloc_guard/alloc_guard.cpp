// The program's allocation functions, charging the rawlog reader's budget (read_budget.h): the
// replaceable global operator new / delete (C++ [new.delete]) and MRPT's aligned allocator
// (mrpt::aligned_malloc / aligned_calloc, which MRPT's containers call through the dynamic
// linker: the definitions here, exported from the executable, take precedence over
// libmrpt-core's). Over budget, or out of memory, they throw std::bad_alloc before allocating;
// MRPT's own aligned allocator would return null and its callers write through it.
//
// Linked into every executable that reads rawlogs (the apps, the tests, the fuzz harness):
// target_link_libraries(<exe> PRIVATE freeinit_alloc_guard).
#include <freeinit/mrpt_plugins/read_budget.h>

#include <cstdlib>
#include <cstring>
#include <new>

namespace {

using freeinit::mrpt_plugins::ReadBudget;

[[maybe_unused]] const bool g_marked = [] {
  ReadBudget::markEnforced();
  return true;
}();

void* allocate(std::size_t size, std::size_t alignment) {
  if (size == 0) size = 1;
  if (!ReadBudget::charge(size)) throw std::bad_alloc();
  for (;;) {
    void* p = nullptr;
    if (alignment <= alignof(std::max_align_t)) {
      p = std::malloc(size);
    } else if (posix_memalign(&p, alignment, size) != 0) {
      p = nullptr;
    }
    if (p != nullptr) return p;
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

void* allocateNoThrow(std::size_t size, std::size_t alignment) noexcept {
  try {
    return allocate(size, alignment);
  } catch (...) {
    return nullptr;
  }
}

constexpr std::size_t kDefault = alignof(std::max_align_t);

}  // namespace

void* operator new(std::size_t n) { return allocate(n, kDefault); }
void* operator new[](std::size_t n) { return allocate(n, kDefault); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  return allocateNoThrow(n, kDefault);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  return allocateNoThrow(n, kDefault);
}
void* operator new(std::size_t n, std::align_val_t a) {
  return allocate(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a) {
  return allocate(n, static_cast<std::size_t>(a));
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocateNoThrow(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocateNoThrow(n, static_cast<std::size_t>(a));
}

void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

// MRPT 2.5.8's aligned allocator (mrpt/core/aligned_allocator.h): same contract, but it throws
// instead of returning null. Freed by mrpt::aligned_free (free()).
namespace mrpt {
void* aligned_malloc(std::size_t size, std::size_t alignment) {
  return allocate(size, alignment < sizeof(void*) ? sizeof(void*) : alignment);
}
void* aligned_calloc(std::size_t bytes, std::size_t alignment) {
  void* p = aligned_malloc(bytes, alignment);
  std::memset(p, 0, bytes);
  return p;
}
}  // namespace mrpt
