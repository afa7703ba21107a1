# The Debian package, by CPack's DEB generator (docs/packaging.md says why this and not
# dpkg-buildpackage): the install rules of cmake/CalstandInstall.cmake staged and wrapped, the
# maintainer scripts and conffiles of packaging/debian/. scripts/package-deb.sh drives it.

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME calstand)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "${CALSTAND_DEB_MAINTAINER}")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_PACKAGE_DIRECTORY ${PROJECT_BINARY_DIR}/cpack)
# Stripped: the programs' debug information is most of their size (lintian wants it gone).
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # calstand_VERSION_ARCH.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION
    "IMU test and calibration station\n\
calstand drives a rate table, a thermal chamber and the inertial measurement\n\
units on them through test and calibration procedures, keeps every sample in\n\
a SQLite database, fits the IMUs' error models and writes calibration\n\
records, certificates and exports.\n\
.\n\
This package holds the station daemon calstandd with its control API, web\n\
console and systemd unit (not enabled), and the command line calstand.")
# The shared libraries' Debian packages by name, from the programs' ELF dependencies.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# adduser: postinst makes the system user. (deb-systemd-helper and -invoke come with
# init-system-helpers, essential in Debian: a dependency on it is an error to lintian.)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "gnuplot-nox, chromium, sqlite3")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/packaging/debian/conffiles
    ${PROJECT_SOURCE_DIR}/packaging/debian/postinst
    ${PROJECT_SOURCE_DIR}/packaging/debian/prerm
    ${PROJECT_SOURCE_DIR}/packaging/debian/postrm)
# Control files 0644, scripts 0755, whatever the checkout's modes (lintian checks them).
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_DEBIAN_COMPRESSION_TYPE xz)
include(CPack)
