# `cmake --install` rules: what a station needs on a machine, in the places the Filesystem
# Hierarchy Standard and Debian policy give them (docs/packaging.md lists them). The package
# (scripts/package-deb.sh, cmake/CalstandPackage.cmake) is these rules staged and wrapped.
include(GNUInstallDirs)

# Installed for the system (prefix /usr): systemd's own answer (bookworm: /lib/systemd/system).
# Elsewhere the prefix's lib/systemd/system, which systemd reads for /usr/local too.
if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  find_package(PkgConfig QUIET)
  if(PKG_CONFIG_FOUND)
    pkg_get_variable(CALSTAND_SYSTEMD_UNIT_DIR_DEFAULT systemd systemdsystemunitdir)
  endif()
endif()
if(NOT CALSTAND_SYSTEMD_UNIT_DIR_DEFAULT)
  set(CALSTAND_SYSTEMD_UNIT_DIR_DEFAULT "${CMAKE_INSTALL_PREFIX}/lib/systemd/system")
endif()
set(CALSTAND_SYSTEMD_UNIT_DIR "${CALSTAND_SYSTEMD_UNIT_DIR_DEFAULT}" CACHE PATH
    "Where calstandd.service is installed")

# The program a user runs is in bin; the daemon, started by systemd, in sbin (section 8).
install(TARGETS calstand RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS calstandd RUNTIME DESTINATION ${CMAKE_INSTALL_SBINDIR})

# Both programs carry the schemas and the procedures compiled in; these copies are the
# reference a user reads and the starting point of their own procedures.
file(GLOB CALSTAND_INSTALL_SCHEMAS CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/schemas/*.json)
install(FILES ${CALSTAND_INSTALL_SCHEMAS} ${PROJECT_SOURCE_DIR}/schemas/api.md
        DESTINATION ${CMAKE_INSTALL_DATADIR}/calstand/schemas)
file(GLOB CALSTAND_INSTALL_PROCEDURES CONFIGURE_DEPENDS
     ${PROJECT_SOURCE_DIR}/procedures/library/*.json)
install(FILES ${CALSTAND_INSTALL_PROCEDURES} DESTINATION ${CMAKE_INSTALL_DATADIR}/calstand/procedures)
install(FILES ${PROJECT_SOURCE_DIR}/sim/stations/default.json ${PROJECT_SOURCE_DIR}/sim/stations/demo.json
        DESTINATION ${CMAKE_INSTALL_DATADIR}/calstand/stations)

# The unit names the installed daemon: generated with the install's sbin.
configure_file(${PROJECT_SOURCE_DIR}/daemon/calstandd.service.in
               ${PROJECT_BINARY_DIR}/calstandd.service @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/calstandd.service DESTINATION ${CALSTAND_SYSTEMD_UNIT_DIR})

# The station's configuration (conffiles in the package): the daemon's options and a station
# file that starts on the built-in simulator until the operator describes the real station.
configure_file(${PROJECT_SOURCE_DIR}/packaging/etc/calstandd.conf.in
               ${PROJECT_BINARY_DIR}/calstandd.conf @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/calstandd.conf DESTINATION ${CMAKE_INSTALL_FULL_SYSCONFDIR}/calstand)
install(FILES ${PROJECT_SOURCE_DIR}/sim/stations/default.json
        DESTINATION ${CMAKE_INSTALL_FULL_SYSCONFDIR}/calstand RENAME station.json)

# Man pages and bash completion, generated from the built programs' own --help
# (cmake/CalstandCliDocs.cmake), so that they cannot drift from the options.
install(FILES ${CALSTAND_MAN_DIR}/calstand.1.gz DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
install(FILES ${CALSTAND_MAN_DIR}/calstandd.8.gz DESTINATION ${CMAKE_INSTALL_MANDIR}/man8)
install(FILES ${CALSTAND_COMPLETION_DIR}/calstand ${CALSTAND_COMPLETION_DIR}/calstandd
        DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions)

# The documentation, with Debian's copyright file and a compressed changelog.
file(GLOB CALSTAND_INSTALL_DOCS CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/docs/*.md)
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${CALSTAND_INSTALL_DOCS}
        DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(FILES ${PROJECT_SOURCE_DIR}/packaging/debian/copyright DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(FILES ${CALSTAND_MAN_DIR}/changelog.gz DESTINATION ${CMAKE_INSTALL_DOCDIR})
