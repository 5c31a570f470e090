# cmake -DEXE=<scene> -DFRAMES=<n> -DSCREENSHOT=<png> -DXVFB_RUN=<xvfb-run> -P run_scene.cmake
# Runs one scene for FRAMES frames on a virtual 24-bit display and checks its exit code (the scene's
# own check that its objects were touched) and the PNG it wrote.
file(REMOVE "${SCREENSHOT}")
execute_process(COMMAND "${XVFB_RUN}" -a -s "-screen 0 1024x768x24" "${EXE}" --frames ${FRAMES} --screenshot "${SCREENSHOT}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 170)
message(STATUS "stdout:\n${out}\nstderr:\n${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${EXE} exited with '${rc}'")
endif()
if(NOT EXISTS "${SCREENSHOT}")
  message(FATAL_ERROR "no screenshot written to ${SCREENSHOT}")
endif()
file(READ "${SCREENSHOT}" signature LIMIT 8 HEX)
if(NOT signature STREQUAL "89504e470d0a1a0a")
  message(FATAL_ERROR "${SCREENSHOT} is not a PNG file (starts with ${signature})")
endif()
