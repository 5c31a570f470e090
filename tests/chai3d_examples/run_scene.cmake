# cmake -DEXE=<scene> -DFRAMES=<n> -DSCREENSHOT=<png> -DXVFB_RUN=<xvfb-run> -P run_scene.cmake
# Runs one scene for FRAMES frames on a virtual 24-bit display and checks its exit code (the scene's
# own check that its objects were touched) and the PNG it wrote.
#
# One retry, for one cause only: LeakSanitizer itself failing at exit ("LeakSanitizer has
# encountered a fatal error", its stop-the-world tracer crashing while the GL driver's threads wind
# down; seen once in about 30 ASan runs of these scenes). That is no verdict on the scene, so the
# whole run, leak check included, is repeated once; a leak report, an ASan or UBSan error or a failed
# scene check fails at once.
foreach(attempt 1 2)
  file(REMOVE "${SCREENSHOT}")
  execute_process(COMMAND "${XVFB_RUN}" -a -s "-screen 0 1024x768x24" "${EXE}" --frames ${FRAMES} --screenshot "${SCREENSHOT}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 170)
  message(STATUS "stdout:\n${out}\nstderr:\n${err}")
  if(NOT rc EQUAL 0 AND attempt EQUAL 1 AND err MATCHES "LeakSanitizer has encountered a fatal error"
     AND NOT err MATCHES "ERROR: (LeakSanitizer: detected|AddressSanitizer)" AND NOT err MATCHES "runtime error:")
    message(STATUS "LeakSanitizer failed to run its check (not a leak report): running the scene once more")
    continue()
  endif()
  break()
endforeach()
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
