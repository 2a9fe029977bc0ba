#pragma once
/// \file svg_plot.hpp
/// Inline SVG line charts and HTML helpers for the certification report and the benchmark
/// dashboard. Emitted directly as text (no plotting tool, nothing downloaded at view time).

#include <functional>
#include <string>
#include <vector>

namespace incise::certify {

/// One polyline with markers. x and y have equal length; non-finite points (and, on log axes,
/// non-positive ones) are skipped. Optional error bars: `y_err` empty or the same length as y.
struct Series {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;
  std::vector<double> y_err;  ///< ± half-height of an error bar per point (same units as y)
  bool dashed = false;        ///< dashed line (e.g. a reference / slope guide)
  /// Optional shaded band per point (e.g. min..max over repetitions): both empty or both the
  /// same length as y; drawn as one filled polygon under the line (linear y axis only).
  std::vector<double> band_lo = {}, band_hi = {};
};

/// Axes, size and labels of a chart.
struct PlotOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  bool log_x = false;
  bool log_y = false;
  int width = 520;   ///< pixels
  int height = 300;  ///< pixels
  /// Categorical x axis: when non-empty, x values are indices 0..n−1 labelled by these strings.
  std::vector<std::string> x_categories;
  /// Linear y axis always reaches 0, so heights compare as ratios and noise is not magnified.
  bool include_zero = false;
  /// Small multiple: narrow margins, small fonts, no axis labels and no legend (the caption
  /// outside the chart names it); a categorical x axis labels only its first and last category.
  bool compact = false;
  /// Formats y tick labels and point tooltips (default: 4 significant digits).
  std::function<std::string(double)> y_format;
};

/// An `<svg>` element (class "incise-plot") with axes, ticks, a legend and one polyline per
/// series. The data points are `<circle>` elements with a `<title>` tooltip. When no series has
/// a plottable point the chart says "no data".
std::string svg_line_plot(const std::vector<Series>& series, const PlotOptions& options);

/// Escapes &, <, >, " and ' for HTML text and attribute values.
std::string html_escape(const std::string& s);

/// Opening of a self-contained HTML page (inline CSS) with the given title, up to `<body>`.
std::string html_page_begin(const std::string& title);

/// Closing tags of a page begun with html_page_begin.
std::string html_page_end();

/// Compact number formatting: 4 significant digits, scientific for very small/large values,
/// "—" for NaN.
std::string format_number(double v);

}  // namespace incise::certify
