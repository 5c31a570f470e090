# The finger exoskeleton: each layer's folder joins that layer's library (uhaptics_device_layer).
uhaptics_device_layer(model uhaptics_models)
uhaptics_device_layer(backend uhaptics_backends)
uhaptics_device_layer(renderer uhaptics_renderers)
uhaptics_device_layer(chai3d uhaptics_chai3d_adapters)
uhaptics_device_layer(servo uhaptics_servo_devices)
