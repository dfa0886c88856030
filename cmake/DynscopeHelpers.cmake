# dynscope_add_library(NAME SOURCES ... [DEPS ...] [PRIVATE_DEPS ...])
# One static library per engine/render folder; headers are included as "engine/<dir>/<file>.h".
function(dynscope_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS} dynscope_warnings)
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
endfunction()

# dynscope_add_test(NAME SOURCES ... DEPS ... [LABELS ...] [LOCK NAME])
# One GoogleTest executable; each TEST() becomes its own CTest test (discovered after build).
# Tests sharing a LOCK never run at the same time (e.g. those that bind loopback ports).
function(dynscope_add_test name)
  cmake_parse_arguments(ARG "" "LOCK" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} dynscope_test_support GTest::gtest_main
                                        dynscope_warnings)
  # One label per test ("unit" unless given, e.g. "slow"): the discovery script cannot carry lists.
  set(labels unit)
  if(ARG_LABELS)
    set(labels ${ARG_LABELS})
  endif()
  set(lock)
  if(ARG_LOCK)
    set(lock RESOURCE_LOCK ${ARG_LOCK})
  endif()
  gtest_discover_tests(${name}
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
    PROPERTIES LABELS "${labels}" ENVIRONMENT "DYNSCOPE_SOURCE_DIR=${PROJECT_SOURCE_DIR}" ${lock}
    DISCOVERY_TIMEOUT 60)
endfunction()
