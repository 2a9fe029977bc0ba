#include <incise/certify/frame_plot.hpp>
#include <incise/certify/svg_plot.hpp>

#include <algorithm>
#include <vector>

namespace incise::certify {

namespace {
// Steps that change nothing take microseconds; drawn at this floor, the log axis keeps the
// decades that matter (0.1 ms … seconds) readable.
constexpr double kFloorMs = 0.1;
}  // namespace

std::string frame_time_svg(const scene::SceneRunResult& result, const std::string& title) {
  Series cut, update, frame;
  cut.label = "cut";
  update.label = "solver update (incl. swap)";
  frame.label = "frame = cut + update";
  for (const scene::CutStepRow& c : result.cut_steps) {
    if (c.step == 0) continue;  // the initial factorization and solve
    const double x = c.step;
    cut.x.push_back(x);
    cut.y.push_back(std::max(kFloorMs, 1e3 * c.seconds_cut));
    update.x.push_back(x);
    update.y.push_back(std::max(kFloorMs, 1e3 * c.seconds_update));
    frame.x.push_back(x);
    frame.y.push_back(std::max(kFloorMs, 1e3 * (c.seconds_cut + c.seconds_update)));
  }
  std::vector<Series> series{frame, update, cut};
  if (!frame.x.empty()) {
    Series budget;
    budget.label = "33 ms budget (30 Hz)";
    budget.x = {frame.x.front(), frame.x.back()};
    budget.y = {kFrameBudgetMs, kFrameBudgetMs};
    budget.dashed = true;
    series.push_back(budget);
  }
  PlotOptions o;
  o.title = title + " (wall time; reported, not asserted)";
  o.x_label = "step (sweep triangle)";
  o.y_label = "ms (log; below 0.1 drawn at 0.1)";
  o.log_y = true;  // spikes of seconds and the 33 ms line both readable
  o.width = 760;
  o.height = 360;
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + svg_line_plot(series, o);
}

std::string frame_plot_path(const std::string& csv_path) {
  const std::string ext = ".csv";
  if (csv_path.size() >= ext.size() &&
      csv_path.compare(csv_path.size() - ext.size(), ext.size(), ext) == 0)
    return csv_path.substr(0, csv_path.size() - ext.size()) + "_frames.svg";
  return csv_path + "_frames.svg";
}

}  // namespace incise::certify
