// `incise certify [--quick] [--out DIR] [--filter RE] [--data DIR] [--junit FILE]`: runs the
// verification catalogue (certify/certify.hpp, docs/certify.md) against the bands in
// reference_data/certify/tolerances.json, writes DIR/index.html and DIR/summary.json (and, with
// --junit, a JUnit XML report for CI test viewers), prints one line per check on stdout and
// progress on stderr. Exit 0 all passed; 3 a check out of its band; 2 no check matches the
// filter; 1 no data folder (cli_util.hpp Exit).

#include <incise/certify/certify.hpp>
#include <incise/certify/svg_plot.hpp>
#include <incise/core/error.hpp>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli_util.hpp"
#include "commands.hpp"

namespace incise::cli {

namespace {

struct CertifyOptions {
  bool quick = false;
  std::string out_dir = "out/certify", filter, data_dir, junit;
};

/// `s` with the five XML special characters escaped (attribute and text content).
std::string xml_escape(const std::string& s) {
  std::string r;
  r.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&': r += "&amp;"; break;
      case '<': r += "&lt;"; break;
      case '>': r += "&gt;"; break;
      case '"': r += "&quot;"; break;
      case '\'': r += "&apos;"; break;
      default: r += c;
    }
  }
  return r;
}

std::string seconds_attr(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", s);
  return buf;
}

std::string comparison_line(const certify::JudgedComparison& c) {
  return c.quantity + " = " + certify::format_number(c.value) + (c.passed ? " in [" : " not in [") +
         certify::format_number(c.bounds.min) + ", " + certify::format_number(c.bounds.max) + "]";
}

/// JUnit XML of a certification (the schema Jenkins, GitLab and GitHub test viewers read): one
/// <testsuite> "incise.certify", one <testcase> per check (classname incise.certify, name the
/// check's id, time its seconds), a <failure> (message the headline comparison, text every
/// comparison out of band and the check's detail) for each check that failed.
std::string certify_junit(const certify::CertifySummary& s, const std::string& commit,
                          const std::string& data_dir) {
  char stamp[32] = "";
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  if (gmtime_r(&now, &utc)) std::strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%S", &utc);
  const std::size_t tests = s.results.size();
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<testsuites name=\"incise certify\" tests=\"" << tests << "\" failures=\"" << s.failed
    << "\" errors=\"0\" time=\"" << seconds_attr(s.seconds) << "\">\n"
    << "  <testsuite name=\"incise.certify\" tests=\"" << tests << "\" failures=\"" << s.failed
    << "\" errors=\"0\" skipped=\"0\" time=\"" << seconds_attr(s.seconds) << "\" timestamp=\""
    << stamp << "\">\n"
    << "    <properties>\n"
    << "      <property name=\"catalogue\" value=\"" << (s.quick ? "quick" : "full") << "\"/>\n"
    << "      <property name=\"commit\" value=\"" << xml_escape(commit) << "\"/>\n"
    << "      <property name=\"data\" value=\"" << xml_escape(data_dir) << "\"/>\n"
    << "    </properties>\n";
  for (const auto& r : s.results) {
    x << "    <testcase classname=\"incise.certify\" name=\"" << xml_escape(r.id) << "\" time=\""
      << seconds_attr(r.seconds) << "\"";
    if (r.passed) {
      x << "/>\n";
      continue;
    }
    const certify::JudgedComparison* h = r.headline();
    std::string text;
    for (const auto& c : r.comparisons)
      if (!c.passed) text += comparison_line(c) + "\n";
    text += r.detail;
    x << ">\n      <failure type=\"out-of-band\" message=\""
      << xml_escape(h ? comparison_line(*h) : r.detail) << "\">" << xml_escape(text)
      << "</failure>\n    </testcase>\n";
  }
  x << "  </testsuite>\n</testsuites>\n";
  return x.str();
}

int certify_command(CertifyOptions& opt, Context& ctx) {
  reject_extras(ctx.extras, "certify", [](const std::string& a) {
    return "unknown argument '" + a + "' (see incise certify --help)";
  });
  std::ostream& out = ctx.out;
  std::ostream& info = ctx.log.info();
  const bool verbose = ctx.log.verbosity() == Verbosity::kVerbose;
  const std::string data_dir = find_data_dir(opt.data_dir);
  const std::string commit = git_commit();
  out << "certify: " << (opt.quick ? "quick" : "full") << " catalogue, reference data " << data_dir
      << "\n";
  const certify::CertifySummary s = certify::run_certify(
      data_dir, opt.quick, opt.filter,
      [&info](const std::string& id) { info << "  running " << id << " ..." << std::endl; });
  for (const auto& r : s.results) {
    const int n = static_cast<int>(r.comparisons.size());
    out << (r.passed ? "  PASS  " : "  FAIL  ") << r.id << "  " << (n - r.failed_comparisons())
        << "/" << n << " in band";
    if (const certify::JudgedComparison* h = r.headline())
      out << (h->passed ? "; nearest an end: " : "; ") << comparison_line(*h);
    out << ", " << certify::format_number(r.seconds) << " s\n";
    // Failed checks: every comparison out of band and the detail; -v: every comparison.
    if (r.passed && !verbose) continue;
    for (const auto& c : r.comparisons)
      if ((verbose || !c.passed) && &c != r.headline())
        out << "        " << comparison_line(c) << "\n";
    if (!r.passed) out << "        " << r.detail << "\n";
  }
  write_file_atomic(opt.out_dir + "/index.html", certify::certify_html(s, commit));
  write_file_atomic(opt.out_dir + "/summary.json", certify::certify_json(s, commit).dump(2) + "\n");
  if (!opt.junit.empty()) write_file_atomic(opt.junit, certify_junit(s, commit, data_dir));
  out << "certify: " << s.passed << " passed, " << s.failed << " failed in "
      << certify::format_number(s.seconds) << " s\n";
  out << "certify: report " << opt.out_dir << "/index.html, summary " << opt.out_dir
      << "/summary.json" << (opt.junit.empty() ? "" : ", JUnit " + opt.junit) << "\n";
  if (s.results.empty()) throw CommandLineError("no check matches the filter '" + opt.filter + "'");
  return exit_code(s.failed == 0 ? Exit::kOk : Exit::kNumericalFailure);
}

}  // namespace

Command add_certify_command(CLI::App& root) {
  auto opt = std::make_shared<CertifyOptions>();
  CLI::App* app = root.add_subcommand(
      "certify", "run the verification catalogue, write a report (docs/certify.md)");
  app->add_flag("--quick", opt->quick, "the quick catalogue (smaller meshes, seconds)");
  app->add_option("--out", opt->out_dir, "write DIR/index.html and DIR/summary.json here")
      ->type_name("DIR")
      ->capture_default_str();
  app->add_option("--filter", opt->filter, "run only the checks whose id matches this regex")
      ->type_name("RE");
  CLI::Option* data =
      app->add_option("--data", opt->data_dir,
                      "the data folder (default: $INCISE_DATA_DIR, else reference_data/ beside the "
                      "program in a build tree, else ../share/incise beside the installed program)")
          ->type_name("DIR");
  app->add_option("--junit", opt->junit,
                  "also write a JUnit XML report here (one testcase per check)")
      ->type_name("FILE");
  return {app, [opt, data](Context& ctx) {
            if (data->count() > 0 && opt->data_dir.empty())
              throw CommandLineError("--data expects a folder, got ''");
            return certify_command(*opt, ctx);
          }};
}

}  // namespace incise::cli
