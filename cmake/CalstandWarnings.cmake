# calstand_set_warnings(target): the project's warning set, applied per target so that
# third-party headers (included as SYSTEM by their imported targets) stay quiet.
function(calstand_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                           -Wno-sign-conversion -Wnon-virtual-dtor
                                           -Wold-style-cast)
  # In a unity batch every .cpp but the first counts as a header, and GCC then warns about each
  # class whose members use a type from that file's anonymous namespace; it is still one file.
  if(CALSTAND_UNITY_BUILD AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(${target} PRIVATE -Wno-subobject-linkage)
  endif()
  if(CALSTAND_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
