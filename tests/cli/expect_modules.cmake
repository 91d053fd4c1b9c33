# GDAL and OpenVDB are loaded on demand, as csgtile's modules (csgtile/kernel/module.h): the
# csgtile binary links neither; a run's footprint check reads through the GDAL module (a missing
# layer is named with the layers GDAL lists); without the module the check names it and where
# it was looked for. (The OpenVDB module's absence: tests/cli/assemble_cells.py.)
# Usage: cmake -DBIN=<csgtile> -DWORK=<dir> [-DSANITIZE=ON] -P expect_modules.cmake
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK}/no_module)
file(WRITE ${WORK}/fp.geojson
  "{\"type\":\"FeatureCollection\",\"crs\":{\"type\":\"name\",\"properties\":{\"name\":"
  "\"urn:ogc:def:crs:EPSG::28992\"}},\"features\":[{\"type\":\"Feature\",\"properties\":"
  "{\"id\":\"a\"},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[10,0],[10,10],"
  "[0,10],[0,0]]]}}]}\n")
file(WRITE ${WORK}/run.yaml
  "run:\n  name: gdal_module\n  inputs:\n    - ${WORK}/absent.las\n  output: ${WORK}/out\n"
  "  crs: EPSG:28992\ncity:\n  footprints: ${WORK}/fp.geojson\n  footprints_layer: nope\n")

execute_process(COMMAND ldd ${BIN} RESULT_VARIABLE rc OUTPUT_VARIABLE libs ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "ldd ${BIN} failed: ${err}")
endif()
# (Sanitizer builds link them on purpose: csgtile_sanitizer_links in the top-level CMakeLists.)
foreach(lib libgdal libopenvdb)
  if(NOT SANITIZE AND libs MATCHES "${lib}")
    message(FATAL_ERROR "the csgtile binary links ${lib} itself (it should load its module):\n${libs}")
  endif()
endforeach()

function(check_run env expected)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env ${env} ${BIN} run ${WORK}/run.yaml
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 78)
    message(FATAL_ERROR "expected exit 78 (config), got ${rc}:\n${out}${err}")
  endif()
  string(FIND "${out}${err}" "${expected}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "expected '${expected}' in:\n${out}${err}")
  endif()
  message(STATUS "${env}: ${err}")
endfunction()

check_run("CSGTILE_MODULE_DIR=" "city.footprints: footprints ${WORK}/fp.geojson: no layer 'nope'; its layers: fp")
check_run("CSGTILE_MODULE_DIR=${WORK}/no_module"
          "GDAL, which reads them: the module libcsgtile_gdal.so is not installed (looked in ${WORK}/no_module;")
