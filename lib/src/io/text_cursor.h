#pragma once
// A forward cursor over text mesh files (OBJ, OFF, ASCII PLY/STL). Numbers are parsed with
// std::from_chars (exact, locale-free); line numbers are only computed when an error is reported,
// so the fast path pays nothing for good messages.
#include <lodkit/error.h>

#include <algorithm>
#include <charconv>
#include <cstring>
#include <cmath>
#include <fmt/format.h>
#include <string>
#include <string_view>

namespace lodkit::detail {

class TextCursor {
 public:
  TextCursor(std::string_view text, const std::string& name)
      : begin_(text.data()), p_(text.data()), end_(text.data() + text.size()), name_(name) {}

  const char* pos() const { return p_; }
  bool done() const { return p_ >= end_; }
  void next_char() {
    if (p_ < end_) ++p_;
  }
  char peek() const { return p_ < end_ ? *p_ : '\0'; }

  /// 1-based line number of `at`.
  long long line_of(const char* at) const {
    return 1 + std::count(begin_, std::min(at, end_), '\n');
  }
  [[noreturn]] void fail(const char* at, const std::string& message) const {
    throw Error(fmt::format("{}: line {}: {}", name_, line_of(at), message));
  }
  [[noreturn]] void fail(const std::string& message) const { fail(p_, message); }

  void skip_blanks() {
    while (p_ < end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r')) ++p_;
  }
  /// Skips blanks and newlines.
  void skip_whitespace() {
    while (p_ < end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r' || *p_ == '\n')) ++p_;
  }
  bool at_line_end() {
    skip_blanks();
    return p_ >= end_ || *p_ == '\n' || *p_ == '#';
  }
  void next_line() {
    const void* nl = p_ < end_ ? std::memchr(p_, '\n', static_cast<std::size_t>(end_ - p_)) : nullptr;
    p_ = nl ? static_cast<const char*>(nl) + 1 : end_;
  }
  /// The next run of non-blank characters on this line (empty at the end of the line).
  std::string_view word() {
    skip_blanks();
    const char* s = p_;
    while (p_ < end_ && *p_ != ' ' && *p_ != '\t' && *p_ != '\r' && *p_ != '\n') ++p_;
    return {s, static_cast<std::size_t>(p_ - s)};
  }
  /// Parses a number at the cursor (after blanks); false, cursor unchanged, if there is none.
  bool try_double(double& out) {
    skip_blanks();
    const char* s = p_;
    if (s < end_ && *s == '+') ++s;
    const auto res = std::from_chars(s, end_, out);
    if (res.ec == std::errc::result_out_of_range) {
      fail(p_, fmt::format("number '{}' is out of range", std::string_view(p_, res.ptr - p_)));
    }
    if (res.ec != std::errc() || !ends_token(res.ptr)) return false;
    p_ = res.ptr;
    return true;
  }
  /// A finite number is required here; `what` names it in the message.
  double finite_double(const char* what) {
    const char* at = (skip_blanks(), p_);
    double v;
    if (!try_double(v)) {
      if (at_line_end()) fail(at, fmt::format("missing {}", what));
      fail(at, fmt::format("{} '{}' is not a number", what, word()));
    }
    if (!std::isfinite(v)) fail(at, fmt::format("{} is {} (coordinates must be finite)", what, v));
    return v;
  }
  bool try_integer(long long& out) {
    skip_blanks();
    const char* s = p_;
    if (s < end_ && *s == '+') ++s;
    const auto res = std::from_chars(s, end_, out);
    if (res.ec != std::errc() || !ends_token(res.ptr)) return false;
    p_ = res.ptr;
    return true;
  }
  long long integer(const char* what) {
    const char* at = (skip_blanks(), p_);
    long long v;
    if (!try_integer(v)) {
      if (at_line_end()) fail(at, fmt::format("missing {}", what));
      fail(at, fmt::format("{} '{}' is not an integer", what, word()));
    }
    return v;
  }

 private:
  bool ends_token(const char* q) const {
    return q >= end_ || *q == ' ' || *q == '\t' || *q == '\r' || *q == '\n' || *q == '/' ||
           *q == '#';
  }
  const char* begin_;
  const char* p_;
  const char* end_;
  const std::string& name_;
};

}  // namespace lodkit::detail
