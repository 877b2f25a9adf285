#pragma once

/// @file
/// `ugv::FixedVector<T, N>`: a vector with a compile-time capacity and std::array storage.
///
/// It never allocates: push_back/emplace_back return false when full instead of growing, so it can be used on
/// the frame path. T must be default-constructible (all N slots exist from construction on, as in std::array).
///
/// Thread-safety: thread-compatible (like std::vector: concurrent reads are fine, writes need external sync).
/// RT-safe: yes (no allocation, no system calls), if T's constructors and assignment are.

#include <array>
#include <cstddef>
#include <span>
#include <utility>

#include "ugv/platform/assert.hpp"

namespace ugv {

template <class T, std::size_t N>
class FixedVector {
public:
    using value_type = T;
    using iterator = typename std::array<T, N>::iterator;
    using const_iterator = typename std::array<T, N>::const_iterator;

    /// @brief Append a copy of `value`.
    /// @return false (and no change) when the vector already holds N elements.
    /// Thread-safety: not thread-safe. RT-safe: yes.
    [[nodiscard]] bool push_back(const T& value) noexcept
    {
        if (size_ == N) {
            return false;
        }
        storage_[size_++] = value;
        return true;
    }

    /// @brief Append `T(args...)`, assigned into the next slot.
    /// @return false (and no change) when full.
    /// Thread-safety: not thread-safe. RT-safe: yes, if T's constructor is.
    template <class... Args>
    [[nodiscard]] bool emplace_back(Args&&... args) noexcept
    {
        if (size_ == N) {
            return false;
        }
        storage_[size_++] = T(std::forward<Args>(args)...);
        return true;
    }

    /// @brief Forget all elements (the slots keep their old values until overwritten).
    void clear() noexcept { size_ = 0; }

    [[nodiscard]] std::size_t size() const noexcept { return size_; }
    [[nodiscard]] static constexpr std::size_t capacity() noexcept { return N; }
    [[nodiscard]] bool empty() const noexcept { return size_ == 0; }
    [[nodiscard]] bool full() const noexcept { return size_ == N; }

    /// Element `i`; `i < size()` is a precondition (checked).
    [[nodiscard]] T& operator[](std::size_t i) noexcept
    {
        UGV_EXPECTS(i < size_);
        return storage_[i];
    }
    [[nodiscard]] const T& operator[](std::size_t i) const noexcept
    {
        UGV_EXPECTS(i < size_);
        return storage_[i];
    }

    [[nodiscard]] iterator begin() noexcept { return storage_.begin(); }
    [[nodiscard]] iterator end() noexcept { return storage_.begin() + static_cast<std::ptrdiff_t>(size_); }
    [[nodiscard]] const_iterator begin() const noexcept { return storage_.begin(); }
    [[nodiscard]] const_iterator end() const noexcept { return storage_.begin() + static_cast<std::ptrdiff_t>(size_); }

    /// The used elements as a span.
    [[nodiscard]] std::span<T> span() noexcept { return {storage_.data(), size_}; }
    [[nodiscard]] std::span<const T> span() const noexcept { return {storage_.data(), size_}; }

private:
    std::array<T, N> storage_{};
    std::size_t size_ = 0;
};

} // namespace ugv
