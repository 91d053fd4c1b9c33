# Module boundary check (DESIGN.md §2): kernel <- geo <- worker, config <- worker; inside geo,
# geo/fit (csgtile::fit) sits on geo's core, which sees neither it nor PCL.
# Usage: cmake -DROOT=<source dir> -P check_boundaries.cmake
# Fails (FATAL_ERROR) listing every include a module must not see.
if(NOT ROOT)
  message(FATAL_ERROR "pass -DROOT=<source dir>")
endif()

# Forbidden include prefixes per module directory (regular expressions on the include path).
set(third_party_worker "pcl/|GeographicLib/|gdal|ogr_|ogrsf_|cpl_|curl/|yaml-cpp/|sqlite3|libpq|postgresql/|CLI/|valijson/")
set(rules
  "kernel|${third_party_worker}|openvdb/|tbb/|nlohmann/|csgtile/(geo|fit|config|worker)/"
  "geo|curl/|yaml-cpp/|sqlite3|libpq|postgresql/|CLI/|valijson/|csgtile/(config|worker)/"
  "config|pcl/|GeographicLib/|gdal|ogr_|ogrsf_|cpl_|curl/|sqlite3|libpq|openvdb/|csgtile/(kernel|geo|fit|worker)/")
set(violations "")

function(scan_module module pattern)
  file(GLOB_RECURSE files "${ROOT}/${module}/*.h" "${ROOT}/${module}/*.hpp" "${ROOT}/${module}/*.cpp")
  foreach(f IN LISTS files)
    # kernel/assembly may use OpenVDB and TBB (DESIGN.md §2); nothing else in the kernel may.
    if(module STREQUAL "kernel" AND f MATCHES "/kernel/assembly/")
      set(p "${third_party_worker}|csgtile/(geo|fit|config|worker)/")
    elseif(module STREQUAL "geo" AND NOT f MATCHES "/geo/fit/")
      # geo's core: no PCL and no fitting (the fit room depends on it, not the reverse).
      set(p "${pattern}|pcl/|csgtile/fit/")
    else()
      set(p "${pattern}")
    endif()
    file(STRINGS "${f}" lines REGEX "^[ \t]*#[ \t]*include")
    foreach(line IN LISTS lines)
      if(line MATCHES "#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"]")
        set(inc "${CMAKE_MATCH_1}")
        if(inc MATCHES "^(${p})")
          file(RELATIVE_PATH rel "${ROOT}" "${f}")
          list(APPEND violations "${rel}: includes <${inc}>, which ${module}/ must not see")
        endif()
      endif()
    endforeach()
  endforeach()
  set(violations "${violations}" PARENT_SCOPE)
endfunction()

foreach(rule IN LISTS rules)
  string(FIND "${rule}" "|" bar)
  string(SUBSTRING "${rule}" 0 ${bar} module)
  math(EXPR start "${bar} + 1")
  string(SUBSTRING "${rule}" ${start} -1 pattern)
  if(IS_DIRECTORY "${ROOT}/${module}")
    scan_module(${module} "${pattern}")
  endif()
endforeach()

# Files matching the globs must not have an include matching `pattern` (a regex on the
# include line); each one that does is a violation named `why`.
function(refuse_includes pattern why)
  file(GLOB_RECURSE files ${ARGN})
  foreach(f IN LISTS files)
    file(STRINGS "${f}" lines REGEX "^[ \t]*#[ \t]*include")
    foreach(line IN LISTS lines)
      if(line MATCHES "${pattern}")
        file(RELATIVE_PATH rel "${ROOT}" "${f}")
        set(violations ${violations} "${rel}: ${why}")
      endif()
    endforeach()
  endforeach()
  set(violations ${violations} PARENT_SCOPE)
endfunction()

# Inside the worker, includes run one way too (issue #23): the jobs and what they use (jobs,
# city, export, ops, fetch, publish, queue rooms, the job records) never include the queue
# loop's header (csgtile/worker/run.h); what every job shares is in csgtile/worker/job_support.h.
refuse_includes("#[ \t]*include[ \t]*[<\"](csgtile/worker/run\\.h|run\\.h)[>\"]"
                "includes the queue loop's run.h (an include running back up)"
                "${ROOT}/worker/src/jobs/*" "${ROOT}/worker/src/city/*"
                "${ROOT}/worker/src/export/*" "${ROOT}/worker/src/ops/*"
                "${ROOT}/worker/src/fetch/*" "${ROOT}/worker/src/publish/*"
                "${ROOT}/worker/src/queue/*" "${ROOT}/worker/src/job_records.*")
# The job table (jobs/) runs the city jobs (city/): city/ never includes jobs/ (what both need,
# the job context and the export settings, sits below them in worker/src). Fetching is below
# publishing: fetch/ never includes the publisher (publish/, csgtile/worker/publish.h); what
# both need about files (digests, atomic replacement) is csgtile/worker/files.h.
refuse_includes("#[ \t]*include[ \t]*\"jobs/"
                "includes the job table's room jobs/ (an include running back up)"
                "${ROOT}/worker/src/city/*")
refuse_includes("#[ \t]*include[ \t]*[<\"](publish/|csgtile/worker/publish\\.h)"
                "includes the publisher (fetch is below publishing)" "${ROOT}/worker/src/fetch/*")

# Public headers show only the standard library, Eigen and our own headers: third-party
# types stay out of other modules' interfaces.
file(GLOB_RECURSE public_headers "${ROOT}/*/include/csgtile/*.h")
foreach(f IN LISTS public_headers)
  file(STRINGS "${f}" lines REGEX "^[ \t]*#[ \t]*include")
  foreach(line IN LISTS lines)
    if(line MATCHES "#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"]")
      set(inc "${CMAKE_MATCH_1}")
      if(NOT inc MATCHES "^(csgtile/|Eigen/)" AND inc MATCHES "/")
        file(RELATIVE_PATH rel "${ROOT}" "${f}")
        list(APPEND violations "${rel}: public header includes third-party <${inc}>")
      endif()
    endif()
  endforeach()
endforeach()

if(violations)
  list(JOIN violations "\n  " text)
  message(FATAL_ERROR "module boundary violations:\n  ${text}")
endif()
message(STATUS "module boundaries respected")
