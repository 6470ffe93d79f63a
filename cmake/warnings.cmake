# Warnings are set per target, never globally, so lodkit behaves as a subproject.
function(lodkit_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion-null
                                           -Wno-sign-compare)
  if(LODKIT_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
