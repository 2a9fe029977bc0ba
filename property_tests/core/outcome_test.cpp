/// The one report shape (core/outcome.hpp, docs/design.md §1.5): every numerical outcome report
/// of the library is an Outcome — status, message, ok(), brief() — so callers test and print
/// them the same way.
#include <incise/core/outcome.hpp>
#include <incise/cut/cutter.hpp>
#include <incise/fixtures/cantilever.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/linalg/augmented_system.hpp>
#include <incise/linalg/gmres.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/report.hpp>

#include <gtest/gtest.h>

#include <type_traits>

namespace incise {
namespace {

enum class Light { kGreen, kRed };
const char* to_string(Light l) {
  return l == Light::kGreen ? "green" : "red";
}
using LightOutcome = Outcome<Light, Light::kGreen, Light::kRed>;

TEST(Outcome, StartsAtItsInitialStatusAndOkMeansTheOkValue) {
  LightOutcome o;
  EXPECT_EQ(o.status, Light::kRed);
  EXPECT_FALSE(o.ok());
  o.status = Light::kGreen;
  EXPECT_TRUE(o.ok());
}

TEST(Outcome, BriefIsTheStatusNameAndTheMessageWhenThereIsOne) {
  LightOutcome o;
  EXPECT_EQ(o.brief(), "red");
  o.message = "stop before the line";
  EXPECT_EQ(o.brief(), "red: stop before the line");
}

// True when R derives from some Outcome<S, ok, initial> (deduced from the base).
template <class S, S kOk, S kInitial>
[[maybe_unused]] std::true_type derives_from_outcome(const Outcome<S, kOk, kInitial>*) {
  return {};
}
[[maybe_unused]] std::false_type derives_from_outcome(...) {
  return {};
}
template <class R>
constexpr bool is_outcome() {
  return decltype(derives_from_outcome(static_cast<const R*>(nullptr)))::value;
}
static_assert(!is_outcome<int>(), "the trait must be able to say no");

TEST(Outcome, EveryNumericalReportOfTheLibraryHasTheOneShape) {
  static_assert(is_outcome<solver::SolverReport>());
  static_assert(is_outcome<solver::InnerCgResult>());
  static_assert(is_outcome<solver::JacobiDiagonal>());
  static_assert(is_outcome<solver::EigenEstimate>());
  static_assert(is_outcome<solver::DampingTrial>());
  static_assert(is_outcome<solver::SpectralDamping>());
  static_assert(is_outcome<linalg::GmresReport>());
  static_assert(is_outcome<linalg::AugmentedReport>());
  static_assert(is_outcome<cut::CutStepReport>());
  static_assert(is_outcome<interactive::AugmentedCutStepReport>());
  static_assert(is_outcome<fixtures::CantileverResult>());
  // The names callers print come from each status enum's to_string.
  solver::SolverReport r;
  EXPECT_EQ(r.brief(), "max_iterations");
  r.status = solver::StopReason::kConverged;
  EXPECT_TRUE(r.ok());
  linalg::AugmentedReport a;
  EXPECT_FALSE(a.ok());
  EXPECT_EQ(a.brief(), linalg::to_string(linalg::AugmentedStatus::kNoFactor));
}

}  // namespace
}  // namespace incise
