# calstand_set_warnings(target): the project's warning set, applied per target so that
# third-party headers (included as SYSTEM by their imported targets) stay quiet.
function(calstand_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                           -Wno-sign-conversion -Wnon-virtual-dtor
                                           -Wold-style-cast)
  if(CALSTAND_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
