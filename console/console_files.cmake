# The web console's files, embedded in calstandd (daemon/CMakeLists.txt) and served under
# /console/ by their base names (routes_console.cpp). uPlot comes from npm
# (console/package-lock.json), installed by scripts/setup-deps.sh.
set(calstand_console_dir ${CMAKE_CURRENT_LIST_DIR})
set(calstand_uplot_dir ${calstand_console_dir}/node_modules/uplot/dist)
foreach(vendor_file uPlot.iife.min.js uPlot.min.css)
  if(NOT EXISTS ${calstand_uplot_dir}/${vendor_file})
    message(FATAL_ERROR "console: ${calstand_uplot_dir}/${vendor_file} is missing. Run "
                        "scripts/setup-deps.sh (it runs `npm ci` in console/), then configure again.")
  endif()
endforeach()
set(CALSTAND_CONSOLE_FILES
  ${calstand_console_dir}/index.html
  ${calstand_console_dir}/console.css
  ${calstand_console_dir}/api.js
  ${calstand_console_dir}/app.js
  ${calstand_console_dir}/charts.js
  ${calstand_console_dir}/dom.js
  ${calstand_console_dir}/fleet_page.js
  ${calstand_console_dir}/live.js
  ${calstand_console_dir}/lot_page.js
  ${calstand_console_dir}/loop_page.js
  ${calstand_console_dir}/runs_page.js
  ${calstand_console_dir}/station_page.js
  ${calstand_uplot_dir}/uPlot.iife.min.js
  ${calstand_uplot_dir}/uPlot.min.css
)
