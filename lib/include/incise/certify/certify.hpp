#pragma once
/// \file certify.hpp
/// The verification catalogue behind `incise certify`: a registry of checks that call library
/// code directly, compare against tolerances stored in
/// `reference_data/certify/tolerances.json` (each with its justification), and render an HTML
/// report (tables, inline SVG plots) and a JSON summary.
///
/// A check never passes by default: a missing tolerance, an exception or a numerical failure
/// status makes it fail, with the reason in its detail.

#include <incise/certify/svg_plot.hpp>

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace incise::certify {

/// What checks receive.
struct CertifyContext {
  bool quick = false;         ///< reduced sizes (the whole catalogue well under a minute)
  std::string data_dir;       ///< the reference_data folder
  nlohmann::json tolerances;  ///< parsed tolerances.json ("checks" object)
  /// Tolerance `name` of check `id` (tolerances.json: checks.<id>.<name>). Throws Error when
  /// absent, so a check without a stored tolerance fails.
  double tolerance(const std::string& id, const std::string& name) const;
  /// The justification string stored next to the check's tolerances ("why"), or "".
  std::string why(const std::string& id) const;
};

/// A table in the report.
struct ReportTable {
  std::string caption;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

/// A plot in the report.
struct ReportPlot {
  PlotOptions options;
  std::vector<Series> series;
};

/// What a check's measurement returns: the compared quantity and the evidence behind it. The
/// measurement does not judge itself: run_certify() compares `value` with the stored tolerance.
struct Measurement {
  double value = 0.0;  ///< the compared quantity (worst case over the check's cases)
  /// Side conditions that must hold besides value ≤ tolerance (every solve converged, every
  /// volume positive, the errors decrease, ...); false fails the check.
  bool conditions_ok = true;
  std::string detail;  ///< what was done, and which side condition failed if one did
  std::vector<ReportTable> tables;
  std::vector<ReportPlot> plots;
};

/// A registered check: what it reproduces, the criterion, the name of its bound in
/// `reference_data/certify/tolerances.json` (checks.<id>.<tolerance_name>), and the
/// measurement. It passes iff the tolerance exists, the measurement throws nothing,
/// conditions_ok holds and value ≤ tolerance (a NaN value fails).
struct Check {
  std::string id;
  std::string title;
  std::string source;          ///< thesis / paper section the check reproduces
  std::string comparison;      ///< the criterion, e.g. "max relative volume error <= tolerance"
  std::string tolerance_name;  ///< key of the bound under checks.<id> in tolerances.json
  std::function<Measurement(const CertifyContext&)> measure;
};

/// Outcome of one check (a Check, its Measurement and the verdict).
struct CheckResult {
  std::string id;
  std::string title;
  std::string source;  ///< thesis / paper section the check reproduces
  bool passed = false;
  double value = 0.0;      ///< the compared quantity (worst case)
  double tolerance = 0.0;  ///< its bound
  std::string comparison;  ///< e.g. "max relative volume error <= tolerance"
  std::string detail;      ///< what was done, and why it failed if it did
  std::vector<ReportTable> tables;
  std::vector<ReportPlot> plots;
  double seconds = 0.0;
};

/// The catalogue, in report order.
const std::vector<Check>& certify_catalogue();

/// All results of one certification.
struct CertifySummary {
  bool quick = false;
  std::vector<CheckResult> results;
  int passed = 0;
  int failed = 0;
  double seconds = 0.0;
};

/// Reads `data_dir`/certify/tolerances.json (ParseError when missing or malformed), runs the
/// checks whose id matches `filter` (ECMAScript regex; "" = all), catching exceptions as
/// failures. `progress` (optional) is called before each check with its id.
CertifySummary run_certify(const std::string& data_dir, bool quick, const std::string& filter,
                           const std::function<void(const std::string&)>& progress = {});

/// The report page (self-contained HTML with inline SVG).
std::string certify_html(const CertifySummary& summary, const std::string& commit);

/// Machine-readable summary: per check id, passed, value, tolerance, detail, seconds.
nlohmann::json certify_json(const CertifySummary& summary, const std::string& commit);

}  // namespace incise::certify
