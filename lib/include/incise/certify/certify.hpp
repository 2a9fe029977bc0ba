#pragma once
/// \file certify.hpp
/// The verification catalogue behind `incise certify` (docs/certify.md): a registry of checks
/// that call library code directly and compare what they measure against bands stored in
/// `reference_data/certify/tolerances.json`, each band with its justification; rendered as an
/// HTML report (tables, inline SVG plots) and a JSON summary.
///
/// Every comparison is two-sided: a measured quantity passes iff min ≤ value ≤ max for its
/// band [min, max]. A check never passes by default: a missing band, an exception, a failed side
/// condition or a measurement without comparisons makes it fail, with the reason in its detail.

#include <incise/certify/svg_plot.hpp>
#include <incise/core/environment.hpp>
#include <incise/scene/scene_spec.hpp>

#include <nlohmann/json.hpp>

#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace incise::certify {

/// A closed interval a compared quantity must lie in (tolerances.json:
/// `checks.<id>.<name> = {"band": [min, max], "why": "..."}`).
struct Band {
  double min = 0.0;
  double max = 0.0;
  /// min ≤ v ≤ max (false for NaN).
  bool contains(double v) const { return v >= min && v <= max; }
};

/// What checks receive.
struct CertifyContext {
  bool quick = false;         ///< reduced sizes (the whole quick catalogue in a few seconds)
  std::string data_dir;       ///< the reference_data folder
  nlohmann::json tolerances;  ///< parsed tolerances.json ("checks" object)
  /// Band `name` of check `id`. Throws Error when it is absent or not a pair of finite numbers
  /// with min ≤ max, or when its justification ("why") is missing.
  Band band(const std::string& id, const std::string& name) const;
  /// The justification stored with band `name` of check `id`, or "".
  std::string why(const std::string& id, const std::string& name) const;
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

/// One compared quantity of a measurement: judged against band `band` of its check.
struct Comparison {
  std::string quantity;  ///< what was measured, e.g. "24 x 6 x 6: CG iterations / thesis"
  std::string band;      ///< the band's name under `checks.<id>` in tolerances.json
  double value = std::numeric_limits<double>::quiet_NaN();
};

/// What a check's measurement returns: the compared quantities and the evidence behind them.
/// The measurement does not judge itself: run_certify() compares each value with its band.
struct Measurement {
  std::vector<Comparison> comparisons;  ///< at least one; each judged against its band
  /// Side conditions that must hold besides the comparisons (every solve converged, every
  /// volume positive, ...); false fails the check.
  bool conditions_ok = true;
  std::string detail;  ///< what was done, and which side condition failed if one did
  std::vector<ReportTable> tables;
  std::vector<ReportPlot> plots;
};

/// A registered check: what it reproduces, the criterion, the bands it compares against
/// (read before it runs, so a check with a missing band fails without running) and the
/// measurement.
struct Check {
  std::string id;
  std::string title;
  std::string source;              ///< thesis / paper section the check reproduces
  std::string criterion;           ///< what must hold, in words
  std::vector<std::string> bands;  ///< names of its bands under `checks.<id>` in tolerances.json
  std::function<Measurement(const CertifyContext&)> measure;
};

/// A comparison with its verdict.
struct JudgedComparison {
  std::string quantity;
  std::string band;  ///< the band's name
  double value = std::numeric_limits<double>::quiet_NaN();
  Band bounds;  ///< NaN bounds when the band is missing
  bool passed = false;
  /// Distance to the nearer end of the band as a fraction of its width (0: on an end; < 0:
  /// outside; NaN when the band is missing or the value is NaN). For a band of zero width:
  /// 0 inside, −∞ outside.
  double margin = std::numeric_limits<double>::quiet_NaN();
};

/// Outcome of one check (a Check, its Measurement and the verdict).
struct CheckResult {
  std::string id;
  std::string title;
  std::string source;     ///< thesis / paper section the check reproduces
  std::string criterion;  ///< what must hold, in words
  bool passed = false;
  std::vector<JudgedComparison> comparisons;
  std::string detail;  ///< what was done, and why it failed if it did
  std::vector<ReportTable> tables;
  std::vector<ReportPlot> plots;
  /// Justification of each band the check uses (name, why), from tolerances.json.
  std::vector<std::pair<std::string, std::string>> justifications;
  double seconds = 0.0;
  /// The comparison to show in a one-line summary: the first failing one, else the one with the
  /// smallest margin; nullptr when there is none.
  const JudgedComparison* headline() const;
  /// Comparisons outside their bands.
  int failed_comparisons() const;
};

/// The catalogue, in report order.
const std::vector<Check>& certify_catalogue();

/// The problem check cg_vs_cholmod solves by CG and by CHOLMOD: the thesis §3.3 cantilever
/// (fixtures::kCantilever geometry, E = 1e6 Pa) on 17 × 3 × 5 cubes (quick; 35 × 7 × 9 full),
/// six tetrahedra each — an element count that is not a multiple of 4 — with ν = 0.3 instead
/// of 0 (so that λ enters the stiffness), clamped at x = 0, 3 N in −y split equally over the tip
/// nodes; CG to ‖r‖ ≤ 1e-9‖f_ext‖. Public so that a test can show how far a stiffness error
/// moves the compared solutions.
scene::SceneSpec cg_vs_cholmod_scene(bool quick);

/// All results of one certification.
struct CertifySummary {
  bool quick = false;
  std::vector<CheckResult> results;
  int passed = 0;
  int failed = 0;
  double seconds = 0.0;
  RunEnvironment environment;  ///< machine and build of the run (captured when it started)
};

/// Reads `data_dir`/certify/tolerances.json (ParseError when missing or malformed), runs the
/// checks whose id matches `filter` (ECMAScript regex; "" = all), catching exceptions as
/// failures. A check passes iff all its bands exist, its measurement throws nothing, its side
/// conditions hold, it returned at least one comparison and every comparison's value lies in
/// its band (a NaN value or a missing band fails). `progress` (optional) is called before each
/// check with its id.
CertifySummary run_certify(const std::string& data_dir, bool quick, const std::string& filter,
                           const std::function<void(const std::string&)>& progress = {});

/// The report page (self-contained HTML with inline SVG).
std::string certify_html(const CertifySummary& summary, const std::string& commit);

/// Machine-readable summary: per check id, passed, its judged comparisons (quantity, band,
/// value, min, max, passed), detail, seconds.
nlohmann::json certify_json(const CertifySummary& summary, const std::string& commit);

}  // namespace incise::certify
