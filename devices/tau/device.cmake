# What is specific to this device, added to each layer's library (read by uhaptics_add_device).
target_sources(uhaptics_backends PRIVATE ${CMAKE_CURRENT_LIST_DIR}/tau_definition.cpp)
if(TARGET uhaptics_servo_devices)
  target_sources(uhaptics_servo_devices PRIVATE ${CMAKE_CURRENT_LIST_DIR}/tau_servo_renderer.cpp)
endif()
if(TARGET uhaptics_chai3d_adapters)
  target_sources(uhaptics_chai3d_adapters PRIVATE ${CMAKE_CURRENT_LIST_DIR}/tau_chai3d.cpp)
endif()
