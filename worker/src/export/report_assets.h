#pragma once
/// \file
/// The run report's static assets, compiled into the worker from
/// worker/src/export/report_assets/ by its embed.cmake (generated report_assets.cpp).
///
/// Internal API of the worker (export/report.cpp); not installed.

#include <string_view>

namespace csgtile::worker::detail {

/// report/report.css: the page's style (csgtile's own).
std::string_view report_stylesheet();
/// report/report.js: the page's script (csgtile's own): stage timings, cell selection, and
/// loading a cell's GLB into the 3D view.
std::string_view report_script();
/// report/viewer.js: three.js with GLTFLoader and OrbitControls and csgtile's glue
/// (viewer_entry.js), one classic script defining window.csgtileViewer. Empty when this
/// binary was built without three and esbuild (the report then has no 3D view).
std::string_view report_viewer_script();
/// The bundled viewer library and its version ("three 0.187.0"), or empty as above.
std::string_view report_viewer_library();

}  // namespace csgtile::worker::detail
