// certify_mutant_<id> DATA_DIR: the quick `incise certify` catalogue, run in an executable that
// links one mutated library source (mutations/<id>.mutation) ahead of the library, printing one
// line per check: "<check id> PASS" or "<check id> FAIL", each failing comparison below its check
// as "# <quantity> = <value> not in [min, max]". certify_mutant_none links no mutation.
// Used by certify_mutation_test (docs/certify.md, "Mutation test").

#include <incise/certify/certify.hpp>

#include <iostream>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: certify_mutant_<id> REFERENCE_DATA_DIR\n";
    return 2;
  }
  try {
    const incise::certify::CertifySummary s = incise::certify::run_certify(argv[1], true, "");
    for (const auto& r : s.results) {
      std::cout << r.id << (r.passed ? " PASS" : " FAIL") << "\n";
      for (const auto& c : r.comparisons)
        if (!c.passed)
          std::cout << "# " << c.quantity << " = " << c.value << " not in [" << c.bounds.min << ", "
                    << c.bounds.max << "]\n";
      if (!r.passed && r.failed_comparisons() == 0) std::cout << "# " << r.detail << "\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "certify_mutant: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
