# Generates the OpenGL 4.5 core loader with Debian's python3-glad at configure time. The generator runs offline
# (--reproducible uses its bundled gl.xml). Generated files live in the build tree and are never committed.
set(DRAPE_GLAD_DIR ${CMAKE_BINARY_DIR}/glad)
set(DRAPE_GLAD_INCLUDE_DIR ${DRAPE_GLAD_DIR}/include)
set(DRAPE_GLAD_SOURCES ${DRAPE_GLAD_DIR}/src/gl.c)
if(NOT EXISTS ${DRAPE_GLAD_SOURCES})
  find_program(DRAPE_SYSTEM_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
  if(NOT DRAPE_SYSTEM_PYTHON)
    message(FATAL_ERROR "drape: /usr/bin/python3 not found; run scripts/setup.sh (installs python3-glad)")
  endif()
  execute_process(
    COMMAND ${DRAPE_SYSTEM_PYTHON} -m glad --quiet --api gl:core=4.5 --out-path ${DRAPE_GLAD_DIR} --reproducible c
    RESULT_VARIABLE glad_result OUTPUT_VARIABLE glad_out ERROR_VARIABLE glad_err)
  if(NOT glad_result EQUAL 0 OR NOT EXISTS ${DRAPE_GLAD_SOURCES})
    message(FATAL_ERROR "drape: glad generation failed (${glad_result}). Is python3-glad installed? "
                        "Run scripts/setup.sh.\n${glad_out}\n${glad_err}")
  endif()
  message(STATUS "drape: generated the GL 4.5 core loader in ${DRAPE_GLAD_DIR}")
endif()
