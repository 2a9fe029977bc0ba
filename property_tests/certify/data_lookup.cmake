# ctest driver of the data lookup of `incise certify` (lib/cli/cli_util.hpp find_data_dir,
# docs/install.md): copies the program INCISE into WORKDIR/bin, where no reference_data link lies
# beside it, and requires
#   1. without --data and INCISE_DATA_DIR: exit 1, one stderr line naming both paths tried
#      (WORKDIR/bin/reference_data and WORKDIR/share/incise);
#   2. with WORKDIR/share/incise (a copy of DATA's certify/tolerances.json, the installed
#      layout): exit 0 and "reference data WORKDIR/share/incise" (canonical path) on stdout;
#   3. INCISE_DATA_DIR=DATA takes precedence over WORKDIR/share/incise, --data over both.
# Run with INCISE_DATA_DIR unset (the test's ENVIRONMENT_MODIFICATION).
#   cmake -DINCISE=... -DDATA=<source>/reference_data -DWORKDIR=... -P data_lookup.cmake
file(REMOVE_RECURSE "${WORKDIR}")
file(MAKE_DIRECTORY "${WORKDIR}/bin")
file(COPY "${INCISE}" DESTINATION "${WORKDIR}/bin")
get_filename_component(name "${INCISE}" NAME)
set(program "${WORKDIR}/bin/${name}")
file(REAL_PATH "${WORKDIR}" root)
# -q: nothing on stderr but errors (the progress lines "running ID ..." are on stderr).
set(certify certify -q --quick --filter "^box_volume$" --out "${WORKDIR}/out")

include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)

# 1. Nothing to find: the message names every path tried, on one line.
expect("no data" 1 "^$"
       "^incise certify: cannot find the incise data folder[^\n]*; tried --data \\(not given\\), INCISE_DATA_DIR \\(not set\\), ${root}/bin/reference_data, ${root}/share/incise \\(pass --data DIR or set INCISE_DATA_DIR\\)\n$"
       "${program}" ${certify})

# 2. The installed layout: <prefix>/bin/incise finds <prefix>/share/incise.
file(MAKE_DIRECTORY "${WORKDIR}/share/incise/certify")
file(COPY "${DATA}/certify/tolerances.json" DESTINATION "${WORKDIR}/share/incise/certify")
expect("installed layout" 0 "reference data ${root}/share/incise\n.*PASS  box_volume" "^$"
       "${program}" ${certify})

# 3. Precedence: INCISE_DATA_DIR over the share folder, --data over INCISE_DATA_DIR.
expect("INCISE_DATA_DIR" 0 "reference data ${DATA}\n" "^$"
       ${CMAKE_COMMAND} -E env "INCISE_DATA_DIR=${DATA}" "${program}" ${certify})
expect("--data" 0 "reference data ${root}/share/incise\n" "^$"
       ${CMAKE_COMMAND} -E env "INCISE_DATA_DIR=${WORKDIR}/nowhere" "${program}" ${certify}
       --data "${root}/share/incise")
