// Counts global operator new calls in scope (replacement operators in alloc_counter.cpp).
#pragma once

namespace dynahand::test {

class AllocationCounter {
 public:
  AllocationCounter();
  ~AllocationCounter();
  AllocationCounter(const AllocationCounter&) = delete;
  AllocationCounter& operator=(const AllocationCounter&) = delete;
  long count() const;  // allocations since construction
  // False under AddressSanitizer, which owns operator new (the counter is then not installed).
  static bool supported();
};

}  // namespace dynahand::test
