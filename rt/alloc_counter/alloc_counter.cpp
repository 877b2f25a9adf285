#include "ugv/rt/alloc_counter.hpp"

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <new>

// Sanitizers replace malloc themselves; defining it again would break them, so under ASan/TSan only operator
// new is counted.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define UGV_ALLOC_COUNTER_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define UGV_ALLOC_COUNTER_SANITIZED 1
#endif
#endif
#ifndef UGV_ALLOC_COUNTER_SANITIZED
#define UGV_ALLOC_COUNTER_SANITIZED 0
#endif

#if !UGV_ALLOC_COUNTER_SANITIZED
// glibc's own allocator entry points (exported by libc.so.6 for exactly this use).
// NOLINTBEGIN(readability-identifier-naming): glibc's names, declared as glibc exports
// them
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* ptr, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void* __libc_valloc(std::size_t size);
void* __libc_pvalloc(std::size_t size);
}
// NOLINTEND(readability-identifier-naming)
#endif

namespace {

// Plain globals with constant initialisation: usable before main and in any thread without allocating.
// NOLINTBEGIN(cppcoreguidelines-avoid-non-const-global-variables): the counter's state; a function-local static would
// run its guard inside operator new
std::atomic<int> gActiveScopes{0};
std::atomic<std::size_t> gGlobalCount{0};
thread_local int tActiveScopes = 0;
thread_local std::size_t tThreadCount = 0;
// NOLINTEND(cppcoreguidelines-avoid-non-const-global-variables)

void countOne() noexcept
{
    if (tActiveScopes > 0) {
        ++tThreadCount;
    }
    if (gActiveScopes.load(std::memory_order_relaxed) > 0) {
        gGlobalCount.fetch_add(1, std::memory_order_relaxed);
    }
}

void* rawAlloc(std::size_t size) noexcept
{
#if UGV_ALLOC_COUNTER_SANITIZED
    return std::malloc(size); // NOLINT(cppcoreguidelines-no-malloc): the sanitizer's malloc is the raw one here
#else
    return __libc_malloc(size);
#endif
}

void* rawAlignedAlloc(std::size_t size, std::align_val_t alignment) noexcept
{
#if UGV_ALLOC_COUNTER_SANITIZED
    void* ptr = nullptr;
    return ::posix_memalign(&ptr, static_cast<std::size_t>(alignment), size) == 0 ? ptr : nullptr;
#else
    return __libc_memalign(static_cast<std::size_t>(alignment), size);
#endif
}

void* countedNew(std::size_t size)
{
    countOne();
    void* ptr = rawAlloc(size == 0 ? 1 : size);
    if (ptr == nullptr) {
        // The replaced operator new must report failure by throwing (the standard's contract for it).
        throw std::bad_alloc();
    }
    return ptr;
}

void* countedAlignedNew(std::size_t size, std::align_val_t alignment)
{
    countOne();
    void* ptr = rawAlignedAlloc(size == 0 ? 1 : size, alignment);
    if (ptr == nullptr) {
        throw std::bad_alloc();
    }
    return ptr;
}

} // namespace

// NOLINTBEGIN(cppcoreguidelines-no-malloc, misc-new-delete-overloads) NOLINTJUSTIFICATION: the allocator itself.
void* operator new(std::size_t size)
{
    return countedNew(size);
}
void* operator new[](std::size_t size)
{
    return countedNew(size);
}
void* operator new(std::size_t size, const std::nothrow_t& /*unused*/) noexcept
{
    countOne();
    return rawAlloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& /*unused*/) noexcept
{
    countOne();
    return rawAlloc(size == 0 ? 1 : size);
}
void* operator new(std::size_t size, std::align_val_t alignment)
{
    return countedAlignedNew(size, alignment);
}
void* operator new[](std::size_t size, std::align_val_t alignment)
{
    return countedAlignedNew(size, alignment);
}
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t& /*unused*/) noexcept
{
    countOne();
    return rawAlignedAlloc(size == 0 ? 1 : size, alignment);
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t& /*unused*/) noexcept
{
    countOne();
    return rawAlignedAlloc(size == 0 ? 1 : size, alignment);
}

void operator delete(void* ptr) noexcept
{
    std::free(ptr);
}
void operator delete[](void* ptr) noexcept
{
    std::free(ptr);
}
void operator delete(void* ptr, std::size_t /*size*/) noexcept
{
    std::free(ptr);
}
void operator delete[](void* ptr, std::size_t /*size*/) noexcept
{
    std::free(ptr);
}
void operator delete(void* ptr, const std::nothrow_t& /*unused*/) noexcept
{
    std::free(ptr);
}
void operator delete[](void* ptr, const std::nothrow_t& /*unused*/) noexcept
{
    std::free(ptr);
}
void operator delete(void* ptr, std::align_val_t /*alignment*/) noexcept
{
    std::free(ptr);
}
void operator delete[](void* ptr, std::align_val_t /*alignment*/) noexcept
{
    std::free(ptr);
}
void operator delete(void* ptr, std::size_t /*size*/, std::align_val_t /*alignment*/) noexcept
{
    std::free(ptr);
}
void operator delete[](void* ptr, std::size_t /*size*/, std::align_val_t /*alignment*/) noexcept
{
    std::free(ptr);
}
void operator delete(void* ptr, std::align_val_t /*alignment*/, const std::nothrow_t& /*unused*/) noexcept
{
    std::free(ptr);
}
void operator delete[](void* ptr, std::align_val_t /*alignment*/, const std::nothrow_t& /*unused*/) noexcept
{
    std::free(ptr);
}

#if !UGV_ALLOC_COUNTER_SANITIZED
// The malloc family. free() stays glibc's: every pointer still comes from glibc's allocator.
extern "C" {
void* malloc(std::size_t size)
{
    countOne();
    return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size)
{
    countOne();
    return __libc_calloc(count, size);
}
void* realloc(void* ptr, std::size_t size)
{
    countOne();
    return __libc_realloc(ptr, size);
}
void* memalign(std::size_t alignment, std::size_t size)
{
    countOne();
    return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size)
{
    countOne();
    return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size)
{
    countOne();
    if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0) {
        return EINVAL;
    }
    void* ptr = __libc_memalign(alignment, size);
    if (ptr == nullptr) {
        return ENOMEM;
    }
    *out = ptr;
    return 0;
}
void* valloc(std::size_t size)
{
    countOne();
    return __libc_valloc(size);
}
void* pvalloc(std::size_t size)
{
    countOne();
    return __libc_pvalloc(size);
}
}
#endif
// NOLINTEND(cppcoreguidelines-no-malloc, misc-new-delete-overloads)

namespace ugv::rt {

AllocationScope::AllocationScope() noexcept : start_(gGlobalCount.load(std::memory_order_relaxed))
{
    // Counting starts after the snapshot: what is counted from here on is this scope's (and any other open one's).
    gActiveScopes.fetch_add(1, std::memory_order_relaxed);
}

AllocationScope::~AllocationScope()
{
    gActiveScopes.fetch_sub(1, std::memory_order_relaxed);
}

std::size_t AllocationScope::count() const noexcept
{
    return gGlobalCount.load(std::memory_order_relaxed) - start_;
}

ThreadAllocationScope::ThreadAllocationScope() noexcept : start_(tThreadCount)
{
    ++tActiveScopes;
}

ThreadAllocationScope::~ThreadAllocationScope()
{
    --tActiveScopes;
}

std::size_t ThreadAllocationScope::count() const noexcept
{
    return tThreadCount - start_;
}

bool mallocFamilyCounted() noexcept
{
    return UGV_ALLOC_COUNTER_SANITIZED == 0;
}

} // namespace ugv::rt
