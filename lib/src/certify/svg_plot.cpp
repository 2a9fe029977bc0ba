#include <incise/certify/svg_plot.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace incise::certify {

namespace {

// Colour-blind-safe palette (Okabe–Ito).
const char* const kColors[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                               "#E69F00", "#56B4E9", "#000000", "#F0E442"};

std::string num(double v) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(2) << v;
  return os.str();
}

// "Nice" tick values covering [lo, hi] on a linear axis.
std::vector<double> linear_ticks(double lo, double hi) {
  const double span = hi - lo;
  const double raw = span / 5.0;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  }
  std::vector<double> t;
  for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * span; v += step)
    t.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
  return t;
}

}  // namespace

std::string format_number(double v) {
  if (std::isnan(v)) return "\xE2\x80\x94";  // em dash
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::ostringstream os;
  const double a = std::abs(v);
  if (a != 0.0 && (a < 1e-3 || a >= 1e6))
    os << std::scientific << std::setprecision(3) << v;  // as printf "%.3e"
  else
    os << std::setprecision(4) << v;  // as printf "%.4g"
  return os.str();
}

std::string html_escape(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      case '\'': o += "&#39;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string html_page_begin(const std::string& title) {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
         html_escape(title) +
         "</title>\n<style>\n"
         "body{font-family:system-ui,sans-serif;margin:2em;max-width:1200px;color:#222}\n"
         "table{border-collapse:collapse;margin:1em 0}\n"
         "th,td{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}\n"
         "th{background:#f0f0f0}\n"
         ".pass{color:#006400;font-weight:bold}.fail{color:#b00000;font-weight:bold}\n"
         ".flag{background:#ffe0e0}.skip{color:#777}\n"
         ".plots{display:flex;flex-wrap:wrap;gap:12px}\n"
         "svg.incise-plot{border:1px solid #ddd;background:#fff}\n"
         "code{background:#f6f6f6;padding:0 3px}\n"
         "</style>\n</head>\n<body>\n";
}

std::string html_page_end() {
  return "</body>\n</html>\n";
}

std::string svg_line_plot(const std::vector<Series>& series, const PlotOptions& o) {
  const double ml = o.compact ? 50 : 70, mr = o.compact ? 8 : 12, mt = o.compact ? 8 : 28,
               mb = o.compact ? 18 : 48;  // margins (px)
  const double pw = o.width - ml - mr, ph = o.height - mt - mb;
  auto usable = [&](double x, double y) {
    return std::isfinite(x) && std::isfinite(y) && (!o.log_x || x > 0) && (!o.log_y || y > 0);
  };
  double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo, ylo = xlo, yhi = -xlo;
  for (const Series& s : series) {
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!usable(s.x[i], s.y[i])) continue;
      const double e = i < s.y_err.size() && std::isfinite(s.y_err[i]) ? s.y_err[i] : 0.0;
      const double x = o.log_x ? std::log10(s.x[i]) : s.x[i];
      const double y_lo = s.y[i] - e > 0 || !o.log_y ? s.y[i] - e : s.y[i];
      const double ya = o.log_y ? std::log10(y_lo) : y_lo;
      const double yb = o.log_y ? std::log10(s.y[i] + e) : s.y[i] + e;
      xlo = std::min(xlo, x), xhi = std::max(xhi, x);
      ylo = std::min(ylo, ya), yhi = std::max(yhi, yb);
      if (!o.log_y && i < s.band_lo.size() && i < s.band_hi.size() && std::isfinite(s.band_lo[i]) &&
          std::isfinite(s.band_hi[i]))
        ylo = std::min(ylo, s.band_lo[i]), yhi = std::max(yhi, s.band_hi[i]);
    }
  }
  if (o.include_zero && !o.log_y && ylo <= yhi) ylo = std::min(ylo, 0.0), yhi = std::max(yhi, 0.0);
  std::ostringstream os;
  os << "<svg class=\"incise-plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << o.width
     << "\" height=\"" << o.height << "\" viewBox=\"0 0 " << o.width << " " << o.height
     << "\" role=\"img\" aria-label=\"" << html_escape(o.title) << "\">\n";
  if (!o.compact)
    os << "<text x=\"" << num(o.width / 2.0) << "\" y=\"17\" text-anchor=\"middle\" "
       << "font-size=\"13\" font-weight=\"bold\">" << html_escape(o.title) << "</text>\n";
  if (!(xlo <= xhi)) {
    os << "<text x=\"" << num(o.width / 2.0) << "\" y=\"" << num(o.height / 2.0)
       << "\" text-anchor=\"middle\" fill=\"#777\">no data</text>\n</svg>\n";
    return os.str();
  }
  if (!o.x_categories.empty()) {
    xlo = std::min(xlo, -0.5);
    xhi = std::max(xhi, static_cast<double>(o.x_categories.size()) - 0.5);
  }
  // Pad degenerate ranges, then 5 % margins.
  auto pad = [](double& lo, double& hi, bool log) {
    if (hi - lo <= 1e-12 * std::max(1.0, std::abs(hi))) {
      const double d = log ? 0.5 : std::max(std::abs(hi) * 0.1, 1e-12);
      lo -= d, hi += d;
    }
    const double m = 0.05 * (hi - lo);
    lo -= m, hi += m;
  };
  if (o.x_categories.empty()) pad(xlo, xhi, o.log_x);
  pad(ylo, yhi, o.log_y);
  auto px = [&](double x) { return ml + (x - xlo) / (xhi - xlo) * pw; };
  auto py = [&](double y) { return mt + ph - (y - ylo) / (yhi - ylo) * ph; };

  os << "<rect x=\"" << ml << "\" y=\"" << mt << "\" width=\"" << num(pw) << "\" height=\""
     << num(ph) << "\" fill=\"none\" stroke=\"#444\"/>\n";
  // Ticks.
  auto ticks_for = [](double lo, double hi, bool log) {
    std::vector<double> t;
    if (log) {
      // Decades first; over less than two decades, "nice" mantissas 1-2-5, then 1..9.
      for (double e = std::ceil(lo); e <= std::floor(hi); e += 1.0) t.push_back(e);
      for (const std::vector<double>& mantissas :
           {std::vector<double>{1, 2, 5}, std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8, 9}}) {
        if (t.size() >= 3) break;
        t.clear();
        for (double e = std::floor(lo); e <= std::ceil(hi); e += 1.0)
          for (double m : mantissas) {
            const double v = e + std::log10(m);
            if (v >= lo && v <= hi) t.push_back(v);
          }
      }
      if (t.size() < 2) t = linear_ticks(lo, hi);
    } else {
      t = linear_ticks(lo, hi);
    }
    return t;
  };
  const int fs = o.compact ? 9 : 10;  // tick font size
  auto tick_label = [](double v, bool log) {
    std::ostringstream label;
    label << std::setprecision(4) << (log ? std::pow(10.0, v) : v);  // as printf "%.4g"
    return label.str();
  };
  auto y_text = [&o](double v) { return o.y_format ? o.y_format(v) : format_number(v); };
  for (double t : ticks_for(ylo, yhi, o.log_y)) {
    os << "<line x1=\"" << ml << "\" x2=\"" << num(ml + pw) << "\" y1=\"" << num(py(t))
       << "\" y2=\"" << num(py(t)) << "\" stroke=\"#eee\"/>"
       << "<text x=\"" << ml - 4 << "\" y=\"" << num(py(t) + 4)
       << "\" text-anchor=\"end\" font-size=\"" << fs << "\">"
       << html_escape(o.y_format && !o.log_y ? o.y_format(t) : tick_label(t, o.log_y))
       << "</text>\n";
  }
  if (!o.x_categories.empty()) {
    const std::size_t n = o.x_categories.size();
    std::vector<std::size_t> shown;
    if (o.compact) {
      shown.push_back(0);
      if (n > 1) shown.push_back(n - 1);
    } else {
      for (std::size_t i = 0; i < n; i += std::max<std::size_t>(1, n / 8)) shown.push_back(i);
    }
    for (std::size_t i : shown) {
      const double x = px(static_cast<double>(i));
      const char* anchor = !o.compact || n == 1 ? "middle" : (i == 0 ? "start" : "end");
      os << "<text x=\"" << num(o.compact && n > 1 ? (i == 0 ? ml : ml + pw) : x) << "\" y=\""
         << num(mt + ph + (o.compact ? 12 : 14)) << "\" text-anchor=\"" << anchor
         << "\" font-size=\"9\">" << html_escape(o.x_categories[i]) << "</text>\n";
    }
  } else {
    for (double t : ticks_for(xlo, xhi, o.log_x)) {
      os << "<line x1=\"" << num(px(t)) << "\" x2=\"" << num(px(t)) << "\" y1=\"" << mt
         << "\" y2=\"" << num(mt + ph) << "\" stroke=\"#eee\"/>"
         << "<text x=\"" << num(px(t)) << "\" y=\"" << num(mt + ph + 14)
         << "\" text-anchor=\"middle\" font-size=\"" << fs << "\">" << tick_label(t, o.log_x)
         << "</text>\n";
    }
  }
  if (!o.compact) {
    os << "<text x=\"" << num(ml + pw / 2) << "\" y=\"" << o.height - 6
       << "\" text-anchor=\"middle\" font-size=\"11\">" << html_escape(o.x_label) << "</text>\n";
    os << "<text transform=\"translate(13," << num(mt + ph / 2)
       << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"11\">" << html_escape(o.y_label)
       << "</text>\n";
  }
  auto x_text = [&o](double x) {
    const double r = std::round(x);
    if (!o.x_categories.empty() && r == x && r >= 0 &&
        r < static_cast<double>(o.x_categories.size()))
      return o.x_categories[static_cast<std::size_t>(r)];
    return format_number(x);
  };
  // Series.
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    const char* color = kColors[k % (sizeof kColors / sizeof kColors[0])];
    // Band (linear y only): upper edge left to right, lower edge back.
    if (!o.log_y && !s.band_lo.empty() && s.band_lo.size() == s.y.size() &&
        s.band_hi.size() == s.y.size()) {
      std::ostringstream upper, lower;
      std::vector<std::string> lows;
      for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
        if (!usable(s.x[i], s.y[i]) || !std::isfinite(s.band_lo[i]) || !std::isfinite(s.band_hi[i]))
          continue;
        const double x = px(o.log_x ? std::log10(s.x[i]) : s.x[i]);
        // A one-point band is drawn 6 px wide so that it shows.
        const bool single = s.y.size() == 1;
        upper << num(single ? x - 3 : x) << "," << num(py(s.band_hi[i])) << " ";
        if (single) upper << num(x + 3) << "," << num(py(s.band_hi[i])) << " ";
        if (single) lows.push_back(num(x + 3) + "," + num(py(s.band_lo[i])));
        lows.push_back(num(single ? x - 3 : x) + "," + num(py(s.band_lo[i])));
      }
      for (auto it = lows.rbegin(); it != lows.rend(); ++it) lower << *it << " ";
      if (!lows.empty())
        os << "<polygon class=\"band\" fill=\"" << color << "\" fill-opacity=\"0.22\" stroke=\""
           << color << "\" stroke-opacity=\"0.35\" stroke-width=\"0.5\" points=\"" << upper.str()
           << lower.str() << "\"/>\n";
    }
    std::ostringstream pts, marks;
    const double r = o.compact ? 2.2 : 3;
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!usable(s.x[i], s.y[i])) continue;
      const double x = px(o.log_x ? std::log10(s.x[i]) : s.x[i]);
      const double y = py(o.log_y ? std::log10(s.y[i]) : s.y[i]);
      pts << num(x) << "," << num(y) << " ";
      if (i < s.y_err.size() && std::isfinite(s.y_err[i]) && s.y_err[i] > 0) {
        const double lo = s.y[i] - s.y_err[i], hi = s.y[i] + s.y_err[i];
        if (!o.log_y || lo > 0) {
          const double y1 = py(o.log_y ? std::log10(lo) : lo);
          const double y2 = py(o.log_y ? std::log10(hi) : hi);
          marks << "<line x1=\"" << num(x) << "\" x2=\"" << num(x) << "\" y1=\"" << num(y1)
                << "\" y2=\"" << num(y2) << "\" stroke=\"" << color << "\"/>";
        }
      }
      marks << "<circle cx=\"" << num(x) << "\" cy=\"" << num(y) << "\" r=\"" << r << "\" fill=\""
            << color << "\"><title>" << html_escape(s.label) << (s.label.empty() ? "" : ": ")
            << html_escape(x_text(s.x[i])) << ", " << html_escape(y_text(s.y[i]));
      if (!o.log_y && i < s.band_lo.size() && i < s.band_hi.size() && std::isfinite(s.band_lo[i]) &&
          std::isfinite(s.band_hi[i]))
        marks << " (" << html_escape(y_text(s.band_lo[i])) << " \xE2\x80\x93 "
              << html_escape(y_text(s.band_hi[i])) << ")";
      marks << "</title></circle>";
    }
    os << "<polyline class=\"series\" fill=\"none\" stroke=\"" << color << "\" stroke-width=\"1.5\""
       << (s.dashed ? " stroke-dasharray=\"5,3\"" : "") << " points=\"" << pts.str() << "\"/>\n"
       << marks.str() << "\n";
    if (o.compact) continue;
    // Legend entry.
    const double ly = mt + 12 + 13.0 * static_cast<double>(k);
    os << "<line x1=\"" << num(ml + 8) << "\" x2=\"" << num(ml + 26) << "\" y1=\"" << num(ly - 4)
       << "\" y2=\"" << num(ly - 4) << "\" stroke=\"" << color << "\" stroke-width=\"2\""
       << (s.dashed ? " stroke-dasharray=\"5,3\"" : "") << "/><text x=\"" << num(ml + 30)
       << "\" y=\"" << num(ly) << "\" font-size=\"10\">" << html_escape(s.label) << "</text>\n";
  }
  os << "</svg>\n";
  return os.str();
}

}  // namespace incise::certify
