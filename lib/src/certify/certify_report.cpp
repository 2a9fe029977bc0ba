// The `incise certify` outputs (certify.hpp): the self-contained HTML report (summary table, then
// per check its source, criterion, judged comparisons, the bands' justifications, detail, tables
// and inline SVG plots) and the JSON summary. Rendering only: the checks and their verdicts come
// from run_certify (certify.cpp).

#include <incise/certify/certify.hpp>
#include <incise/certify/svg_plot.hpp>

#include <cmath>
#include <sstream>

#include "certify_checks.hpp"

namespace incise::certify {

using detail::fmt;

namespace {

std::string band_text(const Band& b) {
  return "[" + fmt(b.min) + ", " + fmt(b.max) + "]";
}

/// "quantity = value in [min, max]" of the check's headline comparison, or "—".
std::string headline_text(const CheckResult& r) {
  const JudgedComparison* h = r.headline();
  if (!h) return "—";
  return h->quantity + " = " + fmt(h->value) + (h->passed ? " in " : " not in ") +
         band_text(h->bounds);
}

}  // namespace

std::string certify_html(const CertifySummary& s, const std::string& commit) {
  std::ostringstream os;
  const std::string title = "incise certification report";
  os << html_page_begin(title) << "<h1>" << title << "</h1>\n";
  os << "<p>Commit <code>" << html_escape(commit) << "</code>, " << (s.quick ? "quick" : "full")
     << " catalogue, " << s.results.size() << " checks: <span class=\"pass\">" << s.passed
     << " passed</span>, <span class=\"" << (s.failed ? "fail" : "pass") << "\">" << s.failed
     << " failed</span>, " << fmt(s.seconds) << " s. Bands [min, max] and their justifications: "
     << "<code>reference_data/certify/tolerances.json</code>; docs/certify.md.</p>\n";
  os << "<table id=\"environment\">\n<caption>Environment</caption>\n";
  for (const auto& [key, value] : s.environment.fields())
    os << "<tr><th>" << html_escape(key) << "</th><td>" << html_escape(value) << "</td></tr>\n";
  os << "</table>\n";
  os << "<table id=\"summary\">\n<tr><th>check</th><th>result</th><th>comparisons in band</th>"
     << "<th>first failing, else nearest its band's end</th><th>criterion</th>"
     << "<th>time (s)</th></tr>\n";
  for (const auto& r : s.results) {
    const int n = static_cast<int>(r.comparisons.size());
    os << "<tr><td><a href=\"#" << html_escape(r.id) << "\">" << html_escape(r.title)
       << "</a></td><td class=\"" << (r.passed ? "pass\">PASS" : "fail\">FAIL") << "</td><td>"
       << (n - r.failed_comparisons()) << " / " << n << "</td><td>" << html_escape(headline_text(r))
       << "</td><td>" << html_escape(r.criterion) << "</td><td>" << fmt(r.seconds)
       << "</td></tr>\n";
  }
  os << "</table>\n";
  for (const auto& r : s.results) {
    os << "<section id=\"" << html_escape(r.id) << "\">\n<h2>" << html_escape(r.title)
       << " <span class=\"" << (r.passed ? "pass\">PASS" : "fail\">FAIL") << "</span></h2>\n";
    os << "<p><b>Source:</b> " << html_escape(r.source) << "<br><b>Criterion:</b> "
       << html_escape(r.criterion) << "</p>\n<p>" << html_escape(r.detail) << "</p>\n";
    if (!r.comparisons.empty()) {
      os << "<table>\n<caption>Comparisons</caption>\n<tr><th>quantity</th><th>value</th>"
         << "<th>band</th><th>[min, max]</th><th>result</th></tr>\n";
      for (const auto& c : r.comparisons)
        os << "<tr><td>" << html_escape(c.quantity) << "</td><td>" << fmt(c.value) << "</td><td>"
           << html_escape(c.band) << "</td><td>" << band_text(c.bounds) << "</td><td class=\""
           << (c.passed ? "pass\">in" : "fail\">OUT") << "</td></tr>\n";
      os << "</table>\n";
    }
    if (!r.justifications.empty()) {
      os << "<p><b>Bands:</b></p>\n<ul>\n";
      for (const auto& [band, why] : r.justifications)
        os << "<li><code>" << html_escape(band) << "</code>: " << html_escape(why) << "</li>\n";
      os << "</ul>\n";
    }
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
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  nlohmann::json j;
  j["commit"] = commit;
  j["quick"] = s.quick;
  j["passed"] = s.passed;
  j["failed"] = s.failed;
  j["seconds"] = s.seconds;
  for (const auto& [key, value] : s.environment.fields()) j["environment"][key] = value;
  j["checks"] = nlohmann::json::array();
  for (const auto& r : s.results) {
    nlohmann::json comparisons = nlohmann::json::array();
    for (const auto& c : r.comparisons)
      comparisons.push_back({{"quantity", c.quantity},
                             {"band", c.band},
                             {"value", num(c.value)},
                             {"min", num(c.bounds.min)},
                             {"max", num(c.bounds.max)},
                             {"passed", c.passed}});
    j["checks"].push_back({{"id", r.id},
                           {"title", r.title},
                           {"passed", r.passed},
                           {"criterion", r.criterion},
                           {"comparisons", comparisons},
                           {"detail", r.detail},
                           {"seconds", r.seconds}});
  }
  return j;
}

}  // namespace incise::certify
