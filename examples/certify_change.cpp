// Example (c): certify a change. After changing the library, run the verification catalogue
// (docs/certify.md) — the checks that reproduce the thesis' and the papers' numbers within
// justified bands — and stop on any failure: what `incise certify` does, from code.
//
//   example_certify DATA_DIR [FILTER] [--full]
//
// DATA_DIR: the incise data folder (the source tree's reference_data/, or <prefix>/share/incise
// of an installed incise; CMake: incise_DATA_DIR). FILTER: an ECMAScript regex on the check ids
// (default: all). --full: the full catalogue instead of the quick one. Prints PASS/FAIL per
// check with its headline comparison; exit 0 when every selected check passed, 1 when one
// failed or none matched, 2 on a usage error.

#include <incise/certify/certify.hpp>

#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv) {
  using namespace incise;
  std::string data_dir, filter;
  bool quick = true;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--full") {
      quick = false;
    } else if (data_dir.empty()) {
      data_dir = arg;
    } else if (filter.empty()) {
      filter = arg;
    } else {
      data_dir.clear();
      break;
    }
  }
  if (data_dir.empty()) {
    std::fprintf(stderr, "usage: example_certify DATA_DIR [FILTER] [--full]\n");
    return 2;
  }

  certify::CertifySummary summary;
  try {
    // The library never prints: progress comes through the callback.
    summary = certify::run_certify(data_dir, quick, filter, [](const std::string& id) {
      std::printf("running %s ...\n", id.c_str());
      std::fflush(stdout);
    });
  } catch (const std::exception& e) {  // e.g. tolerances.json missing: a wrong DATA_DIR
    std::fprintf(stderr, "example_certify: %s\n", e.what());
    return 1;
  }

  for (const certify::CheckResult& r : summary.results) {
    std::printf("%s  %-28s %.2f s", r.passed ? "PASS" : "FAIL", r.id.c_str(), r.seconds);
    if (const certify::JudgedComparison* c = r.headline())
      std::printf("  %s = %s %s [%s, %s]", c->quantity.c_str(),
                  certify::format_number(c->value).c_str(), c->passed ? "in" : "not in",
                  certify::format_number(c->bounds.min).c_str(),
                  certify::format_number(c->bounds.max).c_str());
    std::printf("\n");
    if (!r.passed) std::printf("      %s\n", r.detail.c_str());
  }
  std::printf("%d passed, %d failed (%s catalogue, %.2f s)\n", summary.passed, summary.failed,
              quick ? "quick" : "full", summary.seconds);
  if (summary.results.empty()) {
    std::fprintf(stderr, "example_certify: no check matches '%s'\n", filter.c_str());
    return 1;
  }
  return summary.failed == 0 ? 0 : 1;
}
