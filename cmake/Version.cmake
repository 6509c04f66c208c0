# The version both binaries print with --version: the project's, and the tree it was built
# from (`git describe`, when the source is a git checkout with git at hand). Re-read when
# the checkout's HEAD moves.
set(FLOORPOSE_VERSION_STRING "${PROJECT_VERSION}")
find_package(Git QUIET)
if(GIT_FOUND AND EXISTS "${PROJECT_SOURCE_DIR}/.git")
  execute_process(COMMAND "${GIT_EXECUTABLE}" describe --always --dirty
    WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}" OUTPUT_VARIABLE _describe
    OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE _rc)
  if(_rc EQUAL 0 AND _describe)
    set(FLOORPOSE_VERSION_STRING "${PROJECT_VERSION} (${_describe})")
  endif()
  execute_process(COMMAND "${GIT_EXECUTABLE}" rev-parse --git-path HEAD
    WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}" OUTPUT_VARIABLE _head
    OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  execute_process(COMMAND "${GIT_EXECUTABLE}" rev-parse --symbolic-full-name HEAD
    WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}" OUTPUT_VARIABLE _ref
    OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  foreach(_path "${_head}" ".git/${_ref}")
    if(_path AND EXISTS "${PROJECT_SOURCE_DIR}/${_path}")
      set_property(DIRECTORY "${PROJECT_SOURCE_DIR}" APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
                   "${PROJECT_SOURCE_DIR}/${_path}")
    endif()
  endforeach()
endif()
