#pragma once

/// @file
/// Allocation counting: assert (tests) or report (`ugvsense bench`) that nothing was allocated between two points.
///
/// alloc_counter.cpp replaces the global operator new/new[] (plain, nothrow, aligned; the matching deletes too)
/// and, when the build has no AddressSanitizer/ThreadSanitizer, the malloc family (malloc, calloc, realloc,
/// aligned_alloc, posix_memalign, memalign, valloc, pvalloc), forwarding to glibc's __libc_* entry points.
/// Under ASan/TSan the sanitizer owns malloc, so only operator new is counted (mallocFamilyCounted() == false).
/// The object library `ugv_alloc_counter` (rt/CMakeLists.txt) is linked into every test executable and into the
/// `ugvsense` host tool, never into the service: it replaces the process's allocator.
///
/// Example:
///     const ugv::rt::AllocationScope scope;
///     sut.step();
///     EXPECT_EQ(scope.count(), 0U);

#include <cstddef>

namespace ugv::rt {

/// Counts allocations made by ANY thread while at least one AllocationScope is alive. Scopes may nest and
/// overlap; each reports the allocations since its own construction.
/// Thread-safety: thread-safe. RT-safe: yes (two atomic operations).
class AllocationScope {
public:
    AllocationScope() noexcept;
    ~AllocationScope();
    AllocationScope(const AllocationScope&) = delete;
    AllocationScope& operator=(const AllocationScope&) = delete;
    AllocationScope(AllocationScope&&) = delete;
    AllocationScope& operator=(AllocationScope&&) = delete;

    /// @return allocations (any thread) since this scope was constructed.
    [[nodiscard]] std::size_t count() const noexcept;

private:
    std::size_t start_;
};

/// Counts allocations made by the calling thread only, while it is alive (e.g. the thread under test while
/// other threads allocate freely). Thread-safety: thread-bound. RT-safe: yes.
class ThreadAllocationScope {
public:
    ThreadAllocationScope() noexcept;
    ~ThreadAllocationScope();
    ThreadAllocationScope(const ThreadAllocationScope&) = delete;
    ThreadAllocationScope& operator=(const ThreadAllocationScope&) = delete;
    ThreadAllocationScope(ThreadAllocationScope&&) = delete;
    ThreadAllocationScope& operator=(ThreadAllocationScope&&) = delete;

    /// @return allocations by this thread since this scope was constructed.
    [[nodiscard]] std::size_t count() const noexcept;

private:
    std::size_t start_;
};

/// @return true when malloc & co. are counted too (false under ASan/TSan: operator new only).
[[nodiscard]] bool mallocFamilyCounted() noexcept;

} // namespace ugv::rt
