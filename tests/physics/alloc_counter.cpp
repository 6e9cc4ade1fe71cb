// Replacement global operator new/delete that count allocations while an AllocationCounter
// is alive (the "no allocation per step after warm-up" check).
#include "physics/alloc_counter.h"

#include <atomic>
#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__)
#define DYNAHAND_COUNT_ALLOCATIONS 0
#else
#define DYNAHAND_COUNT_ALLOCATIONS 1
#endif

namespace {
std::atomic<int> gActive{0};
std::atomic<long> gAllocations{0};
}  // namespace

#if DYNAHAND_COUNT_ALLOCATIONS
void* operator new(std::size_t size) {
  if (gActive.load(std::memory_order_relaxed) > 0) gAllocations.fetch_add(1);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
#endif

namespace dynahand::test {

AllocationCounter::AllocationCounter() {
  gAllocations = 0;
  gActive.fetch_add(1);
}
AllocationCounter::~AllocationCounter() {
  gActive.fetch_sub(1);
}
long AllocationCounter::count() const {
  return gAllocations.load();
}
bool AllocationCounter::supported() {
  return DYNAHAND_COUNT_ALLOCATIONS != 0;
}

}  // namespace dynahand::test
