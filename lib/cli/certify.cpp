// `incise certify [--quick] [--out DIR] [--filter RE] [--data DIR]`: runs the verification
// catalogue (certify/certify.hpp, docs/certify.md) against the bands in
// reference_data/certify/tolerances.json, writes DIR/index.html and DIR/summary.json, and exits
// non-zero when any check fails.

#include <incise/certify/certify.hpp>
#include <incise/core/error.hpp>

#include <filesystem>
#include <iostream>

#include "cli_util.hpp"
#include "commands.hpp"

namespace incise::cli {

int run_certify_command(const Args& args, std::ostream& out, std::ostream& err) {
  bool quick = false;
  std::string out_dir = "out/certify", filter, data_dir;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--quick") {
      quick = true;
    } else if (a == "--out") {
      out_dir = option_value(args, i, "--out");
    } else if (a == "--filter") {
      filter = option_value(args, i, "--filter");
    } else if (a == "--data") {
      data_dir = option_value(args, i, "--data");
      if (data_dir.empty()) throw UsageError("--data expects a folder, got ''");
    } else if (a == "--help" || a == "-h") {
      out << "usage: incise certify [--quick] [--out DIR] [--filter RE] [--data DIR]\n"
             "Runs the verification catalogue; writes DIR/index.html and DIR/summary.json\n"
             "(default DIR: out/certify). --data: the data folder (default: $INCISE_DATA_DIR,\n"
             "else reference_data/ beside the program in a build tree, else ../share/incise\n"
             "beside the installed program). Exit 1 when a check fails.\n";
      return 0;
    } else {
      throw UsageError("unknown argument '" + a + "' (see incise certify --help)");
    }
  }
  data_dir = find_data_dir(data_dir);
  const std::string commit = git_commit();
  out << "certify: " << (quick ? "quick" : "full") << " catalogue, reference data " << data_dir
      << "\n";
  const certify::CertifySummary s = certify::run_certify(
      data_dir, quick, filter,
      [&out](const std::string& id) { out << "  running " << id << " ..." << std::endl; });
  for (const auto& r : s.results) {
    const int n = static_cast<int>(r.comparisons.size());
    out << (r.passed ? "  PASS  " : "  FAIL  ") << r.id << "  " << (n - r.failed_comparisons())
        << "/" << n << " in band";
    if (const certify::JudgedComparison* h = r.headline())
      out << (h->passed ? "; nearest an end: " : "; ") << h->quantity << " = "
          << certify::format_number(h->value) << (h->passed ? " in [" : " not in [")
          << certify::format_number(h->bounds.min) << ", " << certify::format_number(h->bounds.max)
          << "]";
    out << ", " << certify::format_number(r.seconds) << " s\n";
    if (r.passed) continue;
    for (const auto& c : r.comparisons)
      if (!c.passed && &c != r.headline())
        out << "        " << c.quantity << " = " << certify::format_number(c.value) << " not in ["
            << certify::format_number(c.bounds.min) << ", " << certify::format_number(c.bounds.max)
            << "]\n";
    out << "        " << r.detail << "\n";
  }
  write_file_atomic(out_dir + "/index.html", certify::certify_html(s, commit));
  write_file_atomic(out_dir + "/summary.json", certify::certify_json(s, commit).dump(2) + "\n");
  out << "certify: " << s.passed << " passed, " << s.failed << " failed in "
      << certify::format_number(s.seconds) << " s\n";
  out << "certify: report " << out_dir << "/index.html, summary " << out_dir << "/summary.json\n";
  if (s.results.empty()) {
    err << "incise certify: no check matches the filter\n";
    return 1;
  }
  return s.failed == 0 ? 0 : 1;
}

}  // namespace incise::cli
