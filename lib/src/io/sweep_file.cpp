#include <incise/core/error.hpp>
#include <incise/io/sweep_file.hpp>

#include <cmath>

#include "text_reader.hpp"

namespace incise::io {

std::vector<SweepEvent> read_sweep_file(const std::string& path, double scale) {
  INCISE_CHECK_PARAM(std::isfinite(scale) && scale > 0.0,
                     "read_sweep_file: scale must be finite and > 0");
  detail::TextReader r = detail::TextReader::open(path, '#');
  std::vector<SweepEvent> events;
  while (!r.at_end()) {
    SweepEvent ev;
    if (r.peek() == "end") {
      r.token("end");
      ev.end_incision = true;
      ev.line = r.line();
      r.end_of_line("'end'");
      events.push_back(ev);
      continue;
    }
    static const char* const kWhat[9] = {"nine numbers (ax ay az bx by bz cx cy cz) or 'end'",
                                         "ay",
                                         "az",
                                         "bx",
                                         "by",
                                         "bz",
                                         "cx",
                                         "cy",
                                         "cz"};
    for (int k = 0; k < 9; ++k) {
      const double x = r.real(kWhat[k]);
      if (k == 0) ev.line = r.line();
      if (r.line() != ev.line)
        throw ParseError(r.file(), ev.line,
                         "expected nine numbers (a sweep triangle) or 'end' on one line");
      const double v = scale * x;
      if (!std::isfinite(v)) r.fail("coordinate times the scale is not finite");
      ev.triangle[static_cast<std::size_t>(k / 3)][k % 3] = v;
    }
    r.end_of_line("nine numbers (a sweep triangle)");
    events.push_back(ev);
  }
  return events;
}

}  // namespace incise::io
