# dsoc_target_warnings(<target>): our warning flags, PRIVATE so they never leak
# into consumers of the installed or add_subdirectory'd targets.
function(dsoc_target_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow
    -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual
    -Wno-missing-field-initializers)
  if(DSOC_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
