#pragma once
// Counts heap allocations made by the calling thread. Linking the uhaptics_alloc_probe object
// library replaces the global operator new/delete of the whole program (tests and benchmarks only),
// so "this servo tick allocates nothing" is checked, not assumed.
#include <cstdint>

namespace uhaptics::tools {

/// Allocations made by this thread since it started.
std::uint64_t threadAllocationCount() noexcept;

/// Allocations made by this thread since construction.
class AllocationScope {
 public:
  AllocationScope() noexcept : start_(threadAllocationCount()) {}
  std::uint64_t count() const noexcept { return threadAllocationCount() - start_; }

 private:
  std::uint64_t start_;
};

}  // namespace uhaptics::tools
