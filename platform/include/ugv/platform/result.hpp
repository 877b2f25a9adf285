#pragma once

/// @file
/// `ugv::Result<T, E>`: the error-return vocabulary of the whole project.
///
/// It offers the subset of C++23 `std::expected` that we use (`has_value`, `value`, `error`, `value_or`,
/// `and_then`, `or_else`, `operator*`, `operator->`), with `ugv::Unexpected<E>` in the role of
/// `std::unexpected`, so that moving to C++23 later is a rename. Our code never throws: functions that can
/// fail return a Result, and accessing the wrong alternative is a bug caught by UGV_ASSERT.
///
/// Thread-safety: a value type; as thread-safe as T and E. RT-safe: yes, if T and E do not allocate.

#include <optional>
#include <type_traits>
#include <utility>
#include <variant>

#include "ugv/platform/assert.hpp"

namespace ugv {

/// The error alternative of a Result, as `std::unexpected`.
template <class E>
class Unexpected {
public:
    constexpr explicit Unexpected(E error) : error_(std::move(error)) {}
    constexpr const E& error() const& noexcept { return error_; }
    constexpr E& error() & noexcept { return error_; }
    constexpr E&& error() && noexcept { return std::move(error_); }

private:
    E error_;
};
template <class E>
Unexpected(E) -> Unexpected<E>;

/// Either a value of type T or an error of type E.
template <class T, class E>
class [[nodiscard]] Result {
public:
    using value_type = T;
    using error_type = E;

    // A Result is made implicitly from its value or its Unexpected error, as std::expected is ("return value;").
    // NOLINTBEGIN(google-explicit-constructor): std::expected's implicit conversions, on purpose
    constexpr Result(const T& value) : storage_(std::in_place_index<0>, value) {}
    constexpr Result(T&& value) : storage_(std::in_place_index<0>, std::move(value)) {}
    template <class G>
    constexpr Result(Unexpected<G> error) : storage_(std::in_place_index<1>, static_cast<E>(std::move(error).error()))
    {
    }
    // NOLINTEND(google-explicit-constructor)

    [[nodiscard]] constexpr bool has_value() const noexcept { return storage_.index() == 0; }
    constexpr explicit operator bool() const noexcept { return has_value(); }

    constexpr T& value() &
    {
        UGV_ASSERT(has_value());
        return *std::get_if<0>(&storage_);
    }
    constexpr const T& value() const&
    {
        UGV_ASSERT(has_value());
        return *std::get_if<0>(&storage_);
    }
    constexpr T&& value() &&
    {
        UGV_ASSERT(has_value());
        return std::move(*std::get_if<0>(&storage_));
    }
    constexpr const E& error() const&
    {
        UGV_ASSERT(!has_value());
        return *std::get_if<1>(&storage_);
    }
    constexpr E& error() &
    {
        UGV_ASSERT(!has_value());
        return *std::get_if<1>(&storage_);
    }
    constexpr E&& error() &&
    {
        UGV_ASSERT(!has_value());
        return std::move(*std::get_if<1>(&storage_));
    }

    constexpr T& operator*() & { return value(); }
    constexpr const T& operator*() const& { return value(); }
    constexpr T* operator->() { return &value(); }
    constexpr const T* operator->() const { return &value(); }

    template <class U>
    constexpr T value_or(U&& fallback) const&
    {
        return has_value() ? value() : static_cast<T>(std::forward<U>(fallback));
    }

    /// f(T) -> Result<U, E>; called only with a value, the error passes through.
    template <class F>
    constexpr auto and_then(F&& f) &
    {
        using R = std::remove_cvref_t<std::invoke_result_t<F, T&>>;
        return has_value() ? std::forward<F>(f)(value()) : R(Unexpected<E>(error()));
    }
    template <class F>
    constexpr auto and_then(F&& f) &&
    {
        using R = std::remove_cvref_t<std::invoke_result_t<F, T&&>>;
        return has_value() ? std::forward<F>(f)(std::move(*this).value()) : R(Unexpected<E>(std::move(*this).error()));
    }
    /// f(E) -> Result<T, G>; called only with an error, the value passes through.
    template <class F>
    constexpr auto or_else(F&& f) &&
    {
        using R = std::remove_cvref_t<std::invoke_result_t<F, E&&>>;
        return has_value() ? R(std::move(*this).value()) : std::forward<F>(f)(std::move(*this).error());
    }

private:
    std::variant<T, E> storage_;
};

/// Result of an operation that yields no value.
template <class E>
class [[nodiscard]] Result<void, E> {
public:
    using value_type = void;
    using error_type = E;

    constexpr Result() = default;
    template <class G>
    // NOLINTNEXTLINE(google-explicit-constructor): std::expected's implicit conversion from its error, on purpose
    constexpr Result(Unexpected<G> error) : error_(static_cast<E>(std::move(error).error()))
    {
    }

    [[nodiscard]] constexpr bool has_value() const noexcept { return !error_.has_value(); }
    constexpr explicit operator bool() const noexcept { return has_value(); }
    constexpr void value() const { UGV_ASSERT(has_value()); }
    constexpr const E& error() const&
    {
        UGV_ASSERT(!has_value());
        return *error_;
    }
    constexpr E& error() &
    {
        UGV_ASSERT(!has_value());
        return *error_;
    }

    template <class F>
    constexpr auto and_then(F&& f) const
    {
        using R = std::remove_cvref_t<std::invoke_result_t<F>>;
        return has_value() ? std::forward<F>(f)() : R(Unexpected<E>(*error_));
    }
    template <class F>
    constexpr auto or_else(F&& f) const
    {
        using R = std::remove_cvref_t<std::invoke_result_t<F, const E&>>;
        return has_value() ? R() : std::forward<F>(f)(*error_);
    }

private:
    std::optional<E> error_;
};

} // namespace ugv
