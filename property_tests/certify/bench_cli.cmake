# ctest driver of `incise bench` (lib/cli/bench.cpp, docs/scenes.md "incise bench") on the stand-in
# binaries of fake_bench/ (alpha_bench: BM_alpha/1, BM_alpha/2; beta_bench: BM_beta/1, BM_beta/2).
#   cmake -DINCISE=... -DFAKE=<source>/property_tests/certify/fake_bench -DWORKDIR=... -P bench_cli.cmake
#     1. --filter BM_alpha: exit 0, nothing on stderr, one run folder holding only
#        alpha_bench.json (beta_bench, none of whose benchmarks the filter selects, is skipped:
#        run, it would leave an empty JSON file and the old "not valid JSON" failure), index.html;
#     2. a filter that selects nothing: exit 2 (usage), one stderr line "no benchmark matches",
#        no run folder added;
#     3. --compare with INCISE_COMPARE_PY naming no file: exit 1, one stderr line naming it.
#   cmake -DINCISE=... -DRUNS=<two run folders> -DWORKDIR=... -DMODE=compare -P bench_cli.cmake
#     compare.py on two stored runs: exit 0, its "U Test" line on stdout; reported as skipped
#     (ctest SKIP_REGULAR_EXPRESSION) when /usr/share/benchmark/compare.py (Debian
#     libbenchmark-tools) is not installed.
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)

if(MODE STREQUAL "compare")
  file(MAKE_DIRECTORY "${WORKDIR}")
  if(NOT EXISTS /usr/share/benchmark/compare.py)
    message(STATUS "compare.py not installed (Debian libbenchmark-tools); skipping")
    return()
  endif()
  expect("compare" 0 "fixture_bench.json.*U Test" "^$" "${INCISE}" bench -q --compare ${RUNS})
  return()
endif()

file(REMOVE_RECURSE "${WORKDIR}")
file(MAKE_DIRECTORY "${WORKDIR}")
# -q: nothing on stderr but errors (the progress lines "bench: running ..." are on stderr).
set(bench "${INCISE}" bench -q --bin-dir "${FAKE}" --out "${WORKDIR}" --repetitions 1)
function(expect_run_folders n)
  file(GLOB run_dirs "${WORKDIR}/runs/*")
  list(LENGTH run_dirs found)
  if(NOT found EQUAL n)
    message(FATAL_ERROR "expected ${n} run folder(s), found ${found}: ${run_dirs}")
  endif()
  set(run_dirs "${run_dirs}" PARENT_SCOPE)
endfunction()

# 1. Only the binary with matching benchmarks runs.
expect("filter BM_alpha" 0 "bench: 2 benchmarks in 1 of 2 binaries" "^$"
       ${bench} --filter "BM_alpha")
expect_run_folders(1)
file(GLOB stored RELATIVE "${run_dirs}" "${run_dirs}/*")
if(NOT stored STREQUAL "alpha_bench.json")
  message(FATAL_ERROR "expected only alpha_bench.json in ${run_dirs}, found '${stored}'")
endif()
if(NOT EXISTS "${WORKDIR}/index.html")
  message(FATAL_ERROR "no dashboard ${WORKDIR}/index.html")
endif()

# 2. Nothing selected: a clear message, exit 2, nothing stored.
expect("filter selects nothing" 2 ""
       "^incise bench: no benchmark matches --filter 'BM_gamma' in the 2 binaries under [^\n]*; nothing run or stored\n$"
       ${bench} --filter "BM_gamma")
expect_run_folders(1)  # none added

# 3. compare.py missing.
expect("compare.py missing" 1 ""
       "^incise bench: INCISE_COMPARE_PY=/nonexistent/compare.py: no such file[^\n]*\n$"
       ${CMAKE_COMMAND} -E env INCISE_COMPARE_PY=/nonexistent/compare.py ${bench} --compare last last)
