# Man pages calstand(1) and calstandd(8) and the bash completion of both, generated from the
# programs just built (their --help, walked down every subcommand by cmake/gen_cli_docs.py):
# they cannot drift from the options. Compressed as Debian wants them (gzip -9n: no name, no
# time stamp, so that two builds give the same bytes). Installed by CalstandInstall.cmake.
find_package(Python3 REQUIRED COMPONENTS Interpreter)
find_program(CALSTAND_GZIP gzip REQUIRED)
set(CALSTAND_MAN_DIR ${PROJECT_BINARY_DIR}/man)
set(CALSTAND_COMPLETION_DIR ${PROJECT_BINARY_DIR}/bash-completion)
file(MAKE_DIRECTORY ${CALSTAND_MAN_DIR} ${CALSTAND_COMPLETION_DIR})

set(calstand_cli_docs_outputs)
foreach(prog_section calstand:1 calstandd:8)
  string(REPLACE ":" ";" ps ${prog_section})
  list(GET ps 0 prog)
  list(GET ps 1 section)
  set(page ${CALSTAND_MAN_DIR}/${prog}.${section})
  set(extra ${PROJECT_SOURCE_DIR}/packaging/man/${prog}.${section}.extra)
  add_custom_command(
    OUTPUT ${page}.gz ${CALSTAND_COMPLETION_DIR}/${prog}
    COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/cmake/gen_cli_docs.py $<TARGET_FILE:${prog}>
            ${prog} ${section} ${PROJECT_VERSION} ${page} ${CALSTAND_COMPLETION_DIR}/${prog}
            --extra ${extra}
    COMMAND ${CALSTAND_GZIP} -9nf ${page}
    DEPENDS ${prog} ${PROJECT_SOURCE_DIR}/cmake/gen_cli_docs.py ${extra}
    COMMENT "Man page ${prog}(${section}) and bash completion from ${prog} --help"
    VERBATIM)
  list(APPEND calstand_cli_docs_outputs ${page}.gz ${CALSTAND_COMPLETION_DIR}/${prog})
endforeach()

set(CALSTAND_DEB_MAINTAINER "calstand maintainers <calstand@example.org>" CACHE STRING
    "Maintainer field of the Debian package and its changelog")
# The package's changelog (Debian's format; /usr/share/doc/calstand/changelog.gz).
configure_file(${PROJECT_SOURCE_DIR}/packaging/debian/changelog.in ${CALSTAND_MAN_DIR}/changelog
               @ONLY)
add_custom_command(
  OUTPUT ${CALSTAND_MAN_DIR}/changelog.gz
  COMMAND ${CALSTAND_GZIP} -9nc ${CALSTAND_MAN_DIR}/changelog > ${CALSTAND_MAN_DIR}/changelog.gz
  DEPENDS ${CALSTAND_MAN_DIR}/changelog)
list(APPEND calstand_cli_docs_outputs ${CALSTAND_MAN_DIR}/changelog.gz)
add_custom_target(calstand_cli_docs ALL DEPENDS ${calstand_cli_docs_outputs})
