#pragma once

/// @file
/// `ugv::SpscRing<T, N>`: a bounded, wait-free, single-producer single-consumer ring buffer.
///
/// Exactly one producer thread calls tryPush() (or claim() + commit()) and exactly one consumer thread calls tryPop()
/// (or front() + release()); any thread may call size() (approximate while the other side runs). The in-place pair
/// lets a large entry be written where it is stored and read where it lies, with no copy through a local. When the ring
/// is full, tryPush() returns false and the entry is NOT stored: the producer decides what to do (the RT logger counts
/// the drop). This differs from iceoryx's SpscSofi (overwrite oldest), which needs a CAS on the consumer side; a failed
/// push is cheaper and keeps the consumer's data in order.
///
/// Indices run freely (64-bit, never wrap in practice) and are masked with N-1, so all N slots are usable.
/// The producer publishes a slot with a release store of tail_ after writing it; the consumer reads tail_ with
/// acquire before reading the slot, and releases the slot back with a release store of head_.
///
/// Thread-safety: one producer + one consumer thread, concurrently. RT-safe: yes, wait-free, no allocation.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace ugv {

/// Separation of the producer and consumer indices (one x86-64/ARMv8 cache line). A constant rather than
/// std::hardware_destructive_interference_size, which GCC warns about because it may differ between builds.
inline constexpr std::size_t kCacheLineBytes = 64;

template <class T, std::size_t N>
class SpscRing {
    static_assert(N >= 2 && (N & (N - 1)) == 0, "SpscRing capacity must be a power of two >= 2");
    static_assert(std::is_trivially_copyable_v<T>, "SpscRing stores trivially copyable types only");
    static_assert(std::atomic<std::uint64_t>::is_always_lock_free, "SpscRing needs lock-free 64-bit atomics");

public:
    /// @brief Producer: copy `value` into the ring.
    /// @return false when the ring is full (nothing stored).
    /// Thread-safety: producer thread only. RT-safe: yes (wait-free).
    [[nodiscard]] bool tryPush(const T& value) noexcept
    {
        const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
        const std::uint64_t head = head_.load(std::memory_order_acquire);
        if (tail - head == N) {
            return false;
        }
        buffer_[tail & kMask] = value;
        tail_.store(tail + 1, std::memory_order_release);
        return true;
    }

    /// @brief Consumer: move the oldest entry into `out`.
    /// @return false when the ring is empty (`out` unchanged).
    /// Thread-safety: consumer thread only. RT-safe: yes (wait-free).
    [[nodiscard]] bool tryPop(T& out) noexcept
    {
        const std::uint64_t head = head_.load(std::memory_order_relaxed);
        const std::uint64_t tail = tail_.load(std::memory_order_acquire);
        if (tail == head) {
            return false;
        }
        out = buffer_[head & kMask];
        head_.store(head + 1, std::memory_order_release);
        return true;
    }

    /// @brief Producer: the free slot the next entry goes in, to fill in place and then commit(); nullptr when the
    /// ring is full. The slot holds whatever an earlier entry left there: write every field that matters.
    /// Thread-safety: producer thread only. RT-safe: yes (wait-free).
    [[nodiscard]] T* claim() noexcept
    {
        const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
        const std::uint64_t head = head_.load(std::memory_order_acquire);
        return tail - head == N ? nullptr : &buffer_[tail & kMask];
    }
    /// @brief Producer: makes the slot claim() gave visible to the consumer (only after a non-null claim()).
    void commit() noexcept { tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release); }

    /// @brief Consumer: the oldest entry, to read (or change) in place until release(); nullptr when empty.
    /// Thread-safety: consumer thread only. RT-safe: yes (wait-free).
    [[nodiscard]] T* front() noexcept
    {
        const std::uint64_t head = head_.load(std::memory_order_relaxed);
        const std::uint64_t tail = tail_.load(std::memory_order_acquire);
        return tail == head ? nullptr : &buffer_[head & kMask];
    }
    /// @brief Consumer: gives the slot front() gave back to the producer (only after a non-null front()).
    void release() noexcept { head_.store(head_.load(std::memory_order_relaxed) + 1, std::memory_order_release); }

    /// @brief Number of stored entries; exact when neither side is running, a snapshot otherwise.
    /// Thread-safety: any thread. RT-safe: yes.
    [[nodiscard]] std::size_t size() const noexcept
    {
        const std::uint64_t head = head_.load(std::memory_order_acquire);
        const std::uint64_t tail = tail_.load(std::memory_order_acquire);
        // The two loads are not atomic together: a consumer running between them can make head > tail.
        return tail >= head ? static_cast<std::size_t>(tail - head) : 0;
    }

    [[nodiscard]] static constexpr std::size_t capacity() noexcept { return N; }

private:
    static constexpr std::uint64_t kMask = N - 1;

    alignas(kCacheLineBytes) std::atomic<std::uint64_t> head_{0}; ///< next slot to read; written by the consumer
    alignas(kCacheLineBytes) std::atomic<std::uint64_t> tail_{0}; ///< next slot to write; written by the producer
    alignas(kCacheLineBytes) std::array<T, N> buffer_{};
};

} // namespace ugv
