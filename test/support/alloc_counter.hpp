#pragma once

/// @file
/// Tests count allocations with rt's counter (ugv/rt/alloc_counter.hpp), linked into every test executable.

#include "ugv/rt/alloc_counter.hpp"

namespace ugv::test {
using rt::AllocationScope;
using rt::mallocFamilyCounted;
using rt::ThreadAllocationScope;
} // namespace ugv::test
