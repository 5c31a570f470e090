#pragma once
// What the three uhaptics CHAI3D scenes share: a GLFW window with a CHAI3D world, camera and light,
// a haptic loop, keyboard handling, and a bounded headless mode for screenshots and tests.
//
// Two ways to run:
//   interactive (default)  the haptic loop runs on its own thread as fast as it can; the device's
//                          servo ticks follow the wall clock (cUhapticsDevice real-time mode)
//   --frames N             N graphics frames, then exit; each frame advances the haptic loop by a
//                          fixed 1/60 s of device time (device lock-step: one servo tick per haptic
//                          frame), so a run is the same on any machine, however slow its GL is.
//                          --screenshot file.png saves the last frame (CHAI3D's cImage, PNG).
// The same two options may come from UHAPTICS_SCENE_FRAMES and UHAPTICS_SCENE_SCREENSHOT.
#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "chai3d.h"

struct GLFWwindow;

namespace uhaptics::scenes {

struct SceneOptions {
  int frames = 0;           // 0: until the window is closed
  std::string screenshot;   // PNG written after the last frame (empty: none)
  /// Parses --frames N, --screenshot file.png (and the environment); throws uhaptics::Error.
  static SceneOptions parse(int argc, char** argv);
  bool bounded() const { return frames > 0; }
};

class SceneApp {
 public:
  static constexpr double kFixedFrameTime = 1.0 / 60.0;  // device time per frame when bounded [s]

  /// Opens the window (GL 2.1 context) and creates world, camera, light and a font. Throws
  /// uhaptics::Error when no window or GL context can be had.
  SceneApp(const std::string& a_title, const SceneOptions& a_options, int a_width = 800, int a_height = 500);
  ~SceneApp();
  SceneApp(const SceneApp&) = delete;
  SceneApp& operator=(const SceneApp&) = delete;

  chai3d::cWorld* world() { return m_world; }
  chai3d::cCamera* camera() { return m_camera; }
  chai3d::cFontPtr font() { return m_font; }
  const SceneOptions& options() const { return m_options; }
  /// A text label in the front layer at (a_x, a_y) pixels from the bottom-left corner.
  chai3d::cLabel* addLabel(int a_x, int a_y);

  /// Called with GLFW key codes on press (q and Escape already quit).
  void onKey(std::function<void(int)> a_handler) { m_keyHandler = std::move(a_handler); }

  /// Runs until the window closes, q / Escape, or the frame budget is spent. a_hapticFrame is one
  /// haptic frame (read device, compute forces, apply); a_hapticFramesPerFixedStep of them make
  /// one bounded-mode frame (the device's servo rate x kFixedFrameTime). a_graphicsFrame updates
  /// labels and widgets before each render. Returns after the haptic loop has stopped.
  void run(const std::function<void()>& a_hapticFrame, int a_hapticFramesPerFixedStep,
           const std::function<void()>& a_graphicsFrame);

  /// Frames rendered so far.
  int framesRendered() const { return m_framesRendered; }

 private:
  static void keyCallback(GLFWwindow* a_window, int a_key, int a_scancode, int a_action, int a_mods);
  void renderFrame();
  bool saveScreenshot();

  SceneOptions m_options;
  GLFWwindow* m_window = nullptr;
  chai3d::cWorld* m_world = nullptr;
  chai3d::cCamera* m_camera = nullptr;
  chai3d::cViewport* m_viewport = nullptr;
  chai3d::cFontPtr m_font;
  std::function<void(int)> m_keyHandler;
  int m_framesRendered = 0;
};

/// Haptic frames per bounded-mode frame for a device with servo period a_period [s].
int hapticFramesPerFixedStep(double a_period);

/// Raises a peak shared between the haptic thread (writer) and the graphics thread (reader),
/// lock-free: retries only while another writer raised it in between.
inline void recordPeak(std::atomic<double>& a_peak, double a_value) {
  double seen = a_peak.load();
  while (a_value > seen && !a_peak.compare_exchange_weak(seen, a_value)) {
  }
}

}  // namespace uhaptics::scenes
