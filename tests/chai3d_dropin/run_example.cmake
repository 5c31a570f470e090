cmake_minimum_required(VERSION 3.19)  # string(JSON); quoted arguments are never dereferenced
# Runs one unchanged CHAI3D example headless for a bounded time with a uhaptics device selected, then
# checks what the device recorded. cmake -P run_example.cmake with
#   EXE, DEVICE, SECONDS, STATS (stats file path), XVFB_RUN, TIMEOUT, BACKEND (default sim), EXPECT:
#     rejected  the selection is invalid: the slot must say so, name the choices, and write nothing
#     forces    ticks at the device's servo rate, and forces rendered
#     contacts  as forces, plus at least one contact episode (the scripted hand reached the scene)
file(REMOVE "${STATS}")
set(ENV{UHAPTICS_DEVICE} "${DEVICE}")
set(ENV{UHAPTICS_STATS} "${STATS}")
if(NOT BACKEND)
  set(BACKEND sim)
endif()
set(ENV{UHAPTICS_BACKEND} "${BACKEND}")
math(EXPR _limit "${SECONDS} + 30")
# The examples run until a key is pressed; timeout ends them (exit 124). SIGTERM skips atexit
# handlers, so the stats file checked here is the device's periodic one (every 0.5 s).
execute_process(COMMAND "${XVFB_RUN}" -a "${TIMEOUT}" "${SECONDS}" "${EXE}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT ${_limit})
message(STATUS "exit: ${rc}\nstderr:\n${err}")
if(NOT rc EQUAL 124)
  message(FATAL_ERROR "${EXE} ended with '${rc}' before the ${SECONDS} s limit (expected 124 from timeout)")
endif()

if(EXPECT STREQUAL "rejected")
  if(NOT err MATCHES "uhaptics: invalid device selection: UHAPTICS_DEVICE = '${DEVICE}'")
    message(FATAL_ERROR "the uhaptics slot did not report the invalid selection: is CHAI3D's stub linked instead?")
  endif()
  if(EXISTS "${STATS}")
    message(FATAL_ERROR "a device ran although the selection was invalid")
  endif()
  return()
endif()

if(NOT EXISTS "${STATS}")
  message(FATAL_ERROR "the device wrote no statistics to ${STATS}: the application did not open it")
endif()
file(READ "${STATS}" json)
message(STATUS "stats:\n${json}")
string(JSON device GET "${json}" device)
string(JSON ticks GET "${json}" ticks)
string(JSON seconds GET "${json}" seconds)
string(JSON rate GET "${json}" rate_hz)
string(JSON contacts GET "${json}" contacts)
string(JSON peak GET "${json}" peak_force_N)
string(JSON output GET "${json}" peak_output)
string(JSON backend GET "${json}" backend)
if(NOT device STREQUAL DEVICE OR NOT backend STREQUAL BACKEND)
  message(FATAL_ERROR "stats are from device '${device}' on '${backend}', expected '${DEVICE}' on '${BACKEND}'")
endif()
# The device opens after the window and GL context exist (about 1 s under Xvfb): ask for half a
# second of servo ticks, at no less than half the nominal rate (the haptic thread shares 2 cores with
# Xvfb's software GL).
if(ticks LESS 250 OR rate LESS 250)
  message(FATAL_ERROR "only ${ticks} servo ticks (${rate} Hz) in ${seconds} s")
endif()
# 0.05 N, the statistics' contact threshold: far above numerical noise (free space gives exactly 0),
# below the weakest contact these scenes produce (04-shapes' spheres at 0.4 of the stiffness).
if(peak LESS 0.05 OR output EQUAL 0)
  message(FATAL_ERROR "no force rendered: peak commanded ${peak} N, peak actuator output ${output}")
endif()
if(EXPECT STREQUAL "contacts" AND contacts LESS 1)
  message(FATAL_ERROR "the scripted hand never touched the scene (0 contacts)")
endif()
message(STATUS "ok: ${ticks} ticks at ${rate} Hz, ${contacts} contacts, peak force ${peak} N")
