#pragma once
// Private to the io module: a growing text buffer with exact number formatting, written to a
// file at the end.

#include <incise/core/error.hpp>

#include <charconv>
#include <fstream>
#include <string>

namespace incise::io::detail {

/// Text buffer. Doubles are written in the shortest form that round-trips exactly.
class TextWriter {
 public:
  TextWriter& operator<<(const std::string& s) {
    buf_ += s;
    return *this;
  }
  TextWriter& operator<<(const char* s) {
    buf_ += s;
    return *this;
  }
  TextWriter& operator<<(char c) {
    buf_ += c;
    return *this;
  }
  TextWriter& operator<<(double v) {
    char tmp[32];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
    buf_.append(tmp, r.ptr);
    return *this;
  }
  TextWriter& operator<<(long long v) {
    char tmp[24];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
    buf_.append(tmp, r.ptr);
    return *this;
  }
  TextWriter& operator<<(int v) { return *this << static_cast<long long>(v); }
  TextWriter& operator<<(long v) { return *this << static_cast<long long>(v); }

  /// Writes the buffer to `path`; throws incise::Error when that fails.
  void save(const std::string& path) const {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) throw Error("cannot open '" + path + "' for writing");
    out.write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
    out.close();
    if (!out) throw Error("error writing '" + path + "'");
  }

 private:
  std::string buf_;
};

}  // namespace incise::io::detail
