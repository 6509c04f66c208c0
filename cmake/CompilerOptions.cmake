# Warnings are errors on our own targets only (generated code gets the defaults).
function(floorpose_target_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow
    -Werror)
endfunction()
