// Settings outside their range at construction, where no Status can be returned (a transition
// matrix that is not row-stochastic, federated shares that do not sum to 1, an integrity
// probability outside (0, 1)). With exceptions, the constructor throws std::invalid_argument
// naming the setting. Compiled with -fno-exceptions, it prints that message to stderr and
// aborts. Code that must not stop checks first: each such constructor has a check function
// beside it that returns Problem::invalid_setting (or a more specific Problem) instead, and a
// constructor given settings its check accepted does not fail. A settings struct's check()
// returns a SettingCheck: the Problem and, in words, which setting is out of range. Steps
// (predict, update, mix...) never throw and never abort: they return a Status.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "ctxfuse/core/status.hpp"

#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
#include <stdexcept>
#endif

namespace ctxfuse {

/// A settings struct's verdict on itself: usable, or the Problem (Problem::invalid_setting) and
/// the setting that is out of range, in words (static text: no allocation, no exception).
struct SettingCheck {
  Problem problem = Problem::none;
  std::string_view what{};

  constexpr bool ok() const { return problem == Problem::none; }
  constexpr explicit operator bool() const { return ok(); }
  static constexpr SettingCheck refuse(std::string_view what) { return {Problem::invalid_setting, what}; }
};

}  // namespace ctxfuse

namespace ctxfuse::detail {

/// Throws `error` (an exception type with what()); compiled with -fno-exceptions, prints its
/// message to stderr and aborts. The throwing forms of the readers end here; each has a
/// non-throwing form that returns its problem instead.
template <class Error>
[[noreturn]] void raise(const Error& error) {
#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
  throw error;
#else
  std::fprintf(stderr, "ctxfuse: %s\n", error.what());
  std::abort();
#endif
}

[[noreturn]] inline void invalid_setting(const std::string& what) {
#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
  throw std::invalid_argument(what);
#else
  std::fprintf(stderr, "ctxfuse: invalid setting: %s\n", what.c_str());
  std::abort();
#endif
}

/// A settings struct's verdict where its user is constructed or run: nothing when `check`
/// accepts, else invalid_setting("<who>: <the setting named by check>").
inline void require_setting(const SettingCheck& check, std::string_view who) {
  if (!check) invalid_setting(std::string(who).append(": ").append(check.what));
}

}  // namespace ctxfuse::detail
