# SPDX-License-Identifier: Apache-2.0
# tacse3 viewer: `npm ci` of viewer/web/package-lock.json in a build folder, then copies uPlot's
# browser build into the page's folder (cmake -P, from viewer/CMakeLists.txt). A failure stops
# the build with what to do: the page must not ship with plots silently missing.
# Inputs: NPM, WEB (source folder), WORK (npm folder), OUT (page folder).
file(MAKE_DIRECTORY "${WORK}")
file(COPY "${WEB}/package.json" "${WEB}/package-lock.json" DESTINATION "${WORK}")
execute_process(COMMAND "${NPM}" ci --no-audit --no-fund --ignore-scripts --loglevel=error
                WORKING_DIRECTORY "${WORK}" RESULT_VARIABLE rc)
set(dist "${WORK}/node_modules/uplot/dist")
if(NOT rc EQUAL 0 OR NOT EXISTS "${dist}/uPlot.iife.min.js")
  message(FATAL_ERROR "viewer: `npm ci` in ${WORK} failed (is the npm registry reachable?), so "
                      "uPlot cannot be bundled into the live view. Fix the network or the npm "
                      "proxy, or configure with -DTACSE3_VIEWER_PLOTS=OFF for a page without plots "
                      "(docs/viewer.md).")
endif()
file(COPY "${dist}/uPlot.iife.min.js" "${dist}/uPlot.min.css" DESTINATION "${OUT}")
file(COPY "${WORK}/node_modules/uplot/LICENSE" DESTINATION "${OUT}")
file(RENAME "${OUT}/LICENSE" "${OUT}/uPlot.LICENSE")
