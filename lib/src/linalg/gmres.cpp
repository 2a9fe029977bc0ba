#include <incise/core/error.hpp>
#include <incise/linalg/gmres.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace incise::linalg {

const char* to_string(GmresStatus status) {
  switch (status) {
    case GmresStatus::kConverged: return "converged";
    case GmresStatus::kMaxIterations: return "iteration cap reached";
    case GmresStatus::kStagnated: return "stagnated";
    case GmresStatus::kBreakdown: return "breakdown (singular operator)";
    case GmresStatus::kNonFinite: return "non-finite values";
  }
  return "unknown";
}

GmresReport gmres(const GmresOperator& a, const GmresOperator& precondition,
                  const Eigen::VectorXd& b, Eigen::VectorXd& x, const GmresOptions& options) {
  INCISE_CHECK_PARAM(options.restart >= 1, "gmres: restart must be >= 1");
  INCISE_CHECK_PARAM(options.tolerance > 0, "gmres: tolerance must be positive");
  INCISE_CHECK_PARAM(options.max_iterations >= 0, "gmres: max_iterations must be >= 0");
  GmresReport report;
  const Eigen::Index n = b.size();
  if (x.size() != n) x = Eigen::VectorXd::Zero(n);
  const double b_norm = b.norm();
  if (!std::isfinite(b_norm)) {
    report.status = GmresStatus::kNonFinite;
    return report;
  }
  if (b_norm == 0) {
    x.setZero();
    report.status = GmresStatus::kConverged;
    report.residual_history.push_back(0);
    return report;
  }
  if (!x.allFinite()) {  // a non-finite initial guess is reported, not iterated on
    report.status = GmresStatus::kNonFinite;
    return report;
  }
  const double target = options.tolerance * b_norm;
  Eigen::VectorXd r(n), w(n), z(n);
  if (x.squaredNorm() > 0) {
    a(x, w);
    r = b - w;
  } else {
    r = b;
  }
  double beta = r.norm();
  report.residual_history.push_back(beta / b_norm);
  const int k =
      static_cast<int>(std::min<Eigen::Index>(options.restart, std::max<Eigen::Index>(n, 1)));
  Eigen::MatrixXd v(n, k + 1);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(k + 1, k);
  Eigen::VectorXd cs(k), sn(k), g(k + 1);
  auto apply_m = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
    if (precondition) {
      precondition(in, out);
    } else {
      out = in;
    }
  };
  while (true) {
    if (beta <= target) {
      report.status = GmresStatus::kConverged;
      report.relative_residual = beta / b_norm;
      return report;
    }
    if (report.iterations >= options.max_iterations) {
      report.status = GmresStatus::kMaxIterations;
      report.relative_residual = beta / b_norm;
      return report;
    }
    v.col(0) = r / beta;
    h.setZero();
    g.setZero();
    g(0) = beta;
    int used = 0;
    bool breakdown = false;
    double res = beta;
    for (int j = 0; j < k && report.iterations < options.max_iterations; ++j) {
      apply_m(v.col(j), z);
      a(z, w);
      ++report.iterations;
      if (!w.allFinite()) {
        report.status = GmresStatus::kNonFinite;
        report.relative_residual = res / b_norm;
        return report;
      }
      const double w_norm0 = w.norm();
      for (int i = 0; i <= j; ++i) {  // modified Gram–Schmidt
        h(i, j) = v.col(i).dot(w);
        w -= h(i, j) * v.col(i);
      }
      if (w.norm() < 0.7 * w_norm0) {  // one re-orthogonalisation pass (Kahan's twice-is-enough)
        for (int i = 0; i <= j; ++i) {
          const double c = v.col(i).dot(w);
          h(i, j) += c;
          w -= c * v.col(i);
        }
      }
      h(j + 1, j) = w.norm();
      for (int i = 0; i < j; ++i) {  // previous Givens rotations
        const double t = cs(i) * h(i, j) + sn(i) * h(i + 1, j);
        h(i + 1, j) = -sn(i) * h(i, j) + cs(i) * h(i + 1, j);
        h(i, j) = t;
      }
      const double hh = std::hypot(h(j, j), h(j + 1, j));
      const double sub = h(j + 1, j);
      if (hh == 0) {
        cs(j) = 1;
        sn(j) = 0;
      } else {
        cs(j) = h(j, j) / hh;
        sn(j) = sub / hh;
      }
      h(j, j) = hh;
      h(j + 1, j) = 0;
      g(j + 1) = -sn(j) * g(j);
      g(j) = cs(j) * g(j);
      res = std::abs(g(j + 1));
      report.residual_history.push_back(res / b_norm);
      used = j + 1;
      if (sub <= 1e-14 * std::max(w_norm0, hh)) {
        breakdown = true;
        break;
      }
      v.col(j + 1) = w / sub;
      if (res <= target) break;
    }
    // Solve the small triangular system and update x (right preconditioning: x += M⁻¹ V y).
    Eigen::VectorXd y = g.head(used);
    double dmax = 0, dmin = std::numeric_limits<double>::infinity();
    for (int i = used - 1; i >= 0; --i) {
      for (int c = i + 1; c < used; ++c) y(i) -= h(i, c) * y(c);
      const double d = h(i, i);
      dmax = std::max(dmax, std::abs(d));
      dmin = std::min(dmin, std::abs(d));
      y(i) = d != 0 ? y(i) / d : 0.0;
    }
    report.hessenberg_condition = dmin > 0 ? dmax / dmin : std::numeric_limits<double>::infinity();
    Eigen::VectorXd update = v.leftCols(used) * y;
    apply_m(update, z);
    x += z;
    if (res <= target) {
      report.status = GmresStatus::kConverged;
      report.relative_residual = res / b_norm;
      return report;
    }
    if (breakdown) {
      report.status = GmresStatus::kBreakdown;
      report.relative_residual = res / b_norm;
      return report;
    }
    a(x, w);
    r = b - w;
    const double beta_new = r.norm();
    ++report.restarts;
    if (!std::isfinite(beta_new)) {
      report.status = GmresStatus::kNonFinite;
      report.relative_residual = beta / b_norm;
      return report;
    }
    if (beta_new > options.stagnation_ratio * beta && report.iterations < options.max_iterations) {
      report.status = GmresStatus::kStagnated;
      report.relative_residual = beta_new / b_norm;
      return report;
    }
    beta = beta_new;
  }
}

}  // namespace incise::linalg
