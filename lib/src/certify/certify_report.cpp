// The `incise certify` outputs (certify.hpp): the self-contained HTML report (summary table, then
// per check its source, criterion, detail, tables and inline SVG plots) and the JSON summary.
// Rendering only: the checks and their verdicts come from run_certify (certify.cpp).

#include <incise/certify/certify.hpp>
#include <incise/certify/svg_plot.hpp>

#include <cmath>
#include <sstream>

#include "certify_checks.hpp"

namespace incise::certify {

using detail::fmt;

std::string certify_html(const CertifySummary& s, const std::string& commit) {
  std::ostringstream os;
  const std::string title = "incise certification report";
  os << html_page_begin(title) << "<h1>" << title << "</h1>\n";
  os << "<p>Commit <code>" << html_escape(commit) << "</code>, " << (s.quick ? "quick" : "full")
     << " catalogue, " << s.results.size() << " checks: <span class=\"pass\">" << s.passed
     << " passed</span>, <span class=\"" << (s.failed ? "fail" : "pass") << "\">" << s.failed
     << " failed</span>, " << fmt(s.seconds) << " s. Tolerances: "
     << "<code>reference_data/certify/tolerances.json</code>.</p>\n";
  os << "<table id=\"summary\">\n<tr><th>check</th><th>result</th><th>value</th>"
     << "<th>tolerance</th><th>comparison</th><th>time (s)</th></tr>\n";
  for (const auto& r : s.results) {
    os << "<tr><td><a href=\"#" << html_escape(r.id) << "\">" << html_escape(r.title)
       << "</a></td><td class=\"" << (r.passed ? "pass\">PASS" : "fail\">FAIL") << "</td><td>"
       << fmt(r.value) << "</td><td>" << fmt(r.tolerance) << "</td><td>"
       << html_escape(r.comparison) << "</td><td>" << fmt(r.seconds) << "</td></tr>\n";
  }
  os << "</table>\n";
  for (const auto& r : s.results) {
    os << "<section id=\"" << html_escape(r.id) << "\">\n<h2>" << html_escape(r.title)
       << " <span class=\"" << (r.passed ? "pass\">PASS" : "fail\">FAIL") << "</span></h2>\n";
    os << "<p><b>Source:</b> " << html_escape(r.source) << "<br><b>Criterion:</b> "
       << html_escape(r.comparison) << " (value " << fmt(r.value) << ", tolerance "
       << fmt(r.tolerance) << ")</p>\n<p>" << html_escape(r.detail) << "</p>\n";
    for (const auto& t : r.tables) {
      os << "<table>\n<caption>" << html_escape(t.caption) << "</caption>\n<tr>";
      for (const auto& h : t.header) os << "<th>" << html_escape(h) << "</th>";
      os << "</tr>\n";
      for (const auto& row : t.rows) {
        os << "<tr>";
        for (const auto& c : row) os << "<td>" << html_escape(c) << "</td>";
        os << "</tr>\n";
      }
      os << "</table>\n";
    }
    if (!r.plots.empty()) {
      os << "<div class=\"plots\">\n";
      for (const auto& p : r.plots) os << svg_line_plot(p.series, p.options);
      os << "</div>\n";
    }
    os << "</section>\n";
  }
  os << html_page_end();
  return os.str();
}

nlohmann::json certify_json(const CertifySummary& s, const std::string& commit) {
  nlohmann::json j;
  j["commit"] = commit;
  j["quick"] = s.quick;
  j["passed"] = s.passed;
  j["failed"] = s.failed;
  j["seconds"] = s.seconds;
  j["checks"] = nlohmann::json::array();
  for (const auto& r : s.results) {
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
    j["checks"].push_back({{"id", r.id},
                           {"title", r.title},
                           {"passed", r.passed},
                           {"value", num(r.value)},
                           {"tolerance", num(r.tolerance)},
                           {"comparison", r.comparison},
                           {"detail", r.detail},
                           {"seconds", r.seconds}});
  }
  return j;
}

}  // namespace incise::certify
