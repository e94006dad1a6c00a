// Bit-flag status enums: one definition of `|`, `|=`, `&` and `has` for all of them.
//
// A status enum opts in by specialising `inhand::is_flags` next to its definition:
//
//   enum class IkStatus : unsigned { ok = 0, damped = 1u << 0, limited = 1u << 1 };
//   template <> struct is_flags<IkStatus> : std::true_type {};
//
// Then `IkStatus::damped | IkStatus::limited` combines flags, `has(s, IkStatus::damped)`
// tests one (true when any bit of `flag` is set in `s`; `has(s, ok)` is always false,
// compare `s == ok` instead). The operators are found by argument-dependent lookup
// for every enum of namespace inhand and take part in overload resolution only for
// enums that opted in. Everything is constexpr and noexcept.
#pragma once

#include <type_traits>

namespace inhand {

/// Trait: true for the enums whose values are bit flags (specialise to opt in).
template <typename E>
struct is_flags : std::false_type {};

template <typename E>
using EnableIfFlags = std::enable_if_t<is_flags<E>::value, int>;

template <typename E, EnableIfFlags<E> = 0>
constexpr E operator|(E a, E b) noexcept {
  using U = std::underlying_type_t<E>;
  return static_cast<E>(static_cast<U>(static_cast<U>(a) | static_cast<U>(b)));
}

template <typename E, EnableIfFlags<E> = 0>
constexpr E operator&(E a, E b) noexcept {
  using U = std::underlying_type_t<E>;
  return static_cast<E>(static_cast<U>(static_cast<U>(a) & static_cast<U>(b)));
}

template <typename E, EnableIfFlags<E> = 0>
constexpr E& operator|=(E& a, E b) noexcept {
  a = a | b;
  return a;
}

/// True when any bit of `flag` is set in `s`.
template <typename E, EnableIfFlags<E> = 0>
constexpr bool has(E s, E flag) noexcept {
  using U = std::underlying_type_t<E>;
  return (static_cast<U>(s) & static_cast<U>(flag)) != U(0);
}

}  // namespace inhand
