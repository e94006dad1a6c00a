// Heap-allocation counting for the benchmarks.
//
// alloc_counter.cpp replaces the global operator new (every form) and interposes the
// C allocation functions (malloc, calloc, realloc, aligned_alloc, posix_memalign,
// memalign), because Eigen's dynamic-size storage calls std::malloc directly and would
// escape an operator-new-only count. Each allocation is counted once, whichever entry
// point it came through. Counting is a relaxed atomic increment (a few ns, paid only
// when something allocates, i.e. never in an allocation-free tick).
#pragma once

#include <cstdint>

namespace inhand_bench {

/// Heap allocations made so far by this process (all threads).
std::uint64_t allocation_count() noexcept;

}  // namespace inhand_bench
