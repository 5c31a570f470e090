#include "scene_app.hpp"

#include <GLFW/glfw3.h>
#include <dlfcn.h>
#include <link.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "uhaptics/core/fault.hpp"

namespace uhaptics::scenes {
namespace {

int parseFrames(const std::string& a_text) {
  char* end = nullptr;
  const long value = std::strtol(a_text.c_str(), &end, 10);
  if (a_text.empty() || *end != '\0' || value < 1 || value > 1000000) {
    throw Error("--frames / UHAPTICS_SCENE_FRAMES must be a whole number of frames in [1, 1000000], got '" +
                a_text + "'");
  }
  return static_cast<int>(value);
}

// CHAI3D 3.3's ~cViewport deletes its view panel twice: once with the camera whose front layer holds
// it, once directly. Detaching the panel first leaves one owner, so the viewport can be deleted.
class OwnedViewport : public chai3d::cViewport {
 public:
  using chai3d::cViewport::cViewport;
  ~OwnedViewport() override { m_cameraViewport->m_frontLayer->removeChild(m_viewPanel); }
};

// Keeps every shared library loaded so far (the GL driver the new context pulled in with dlopen:
// Mesa's GLX vendor library, its DRI driver) loaded until the process exits. glfwTerminate()
// otherwise unloads the driver while allocations it keeps through its own globals are still live,
// and an exit-time leak check (LeakSanitizer) then reports them as leaks of an unknown module.
void pinLoadedLibraries() {
  dl_iterate_phdr(
      [](dl_phdr_info* a_info, std::size_t, void*) {
        if (a_info->dlpi_name != nullptr && a_info->dlpi_name[0] != '\0') {
          dlopen(a_info->dlpi_name, RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);  // marks it never to unload
        }
        return 0;
      },
      nullptr);
}

}  // namespace

SceneOptions SceneOptions::parse(int argc, char** argv) {
  SceneOptions options;
  if (const char* frames = std::getenv("UHAPTICS_SCENE_FRAMES"); frames != nullptr && *frames != '\0') {
    options.frames = parseFrames(frames);
  }
  if (const char* shot = std::getenv("UHAPTICS_SCENE_SCREENSHOT"); shot != nullptr) options.screenshot = shot;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--frames" && has_value) {
      options.frames = parseFrames(argv[++i]);
    } else if (arg == "--screenshot" && has_value) {
      options.screenshot = argv[++i];
    } else {
      throw Error("unknown argument '" + arg + "' (usage: " + argv[0] + " [--frames N] [--screenshot file.png])");
    }
  }
  if (!options.screenshot.empty() && options.frames == 0) {
    throw Error("--screenshot needs --frames N (the screenshot is taken after the last frame)");
  }
  return options;
}

int hapticFramesPerFixedStep(double a_period) {
  return std::max(1, static_cast<int>(std::lround(SceneApp::kFixedFrameTime / a_period)));
}

SceneApp::SceneApp(const std::string& a_title, const SceneOptions& a_options, int a_width, int a_height)
    : m_options(a_options) {
  if (!glfwInit()) throw Error("GLFW cannot initialize (no display? run under xvfb-run)");
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 2);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 1);
  glfwWindowHint(GLFW_DOUBLEBUFFER, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, 4);
  m_window = glfwCreateWindow(a_width, a_height, a_title.c_str(), nullptr, nullptr);
  if (m_window == nullptr) {
    glfwTerminate();
    throw Error("GLFW cannot create a " + std::to_string(a_width) + " x " + std::to_string(a_height) + " window");
  }
  glfwSetWindowUserPointer(m_window, this);
  glfwSetKeyCallback(m_window, keyCallback);
  glfwMakeContextCurrent(m_window);
  glfwSwapInterval(m_options.bounded() ? 0 : 1);
#ifdef GLEW_VERSION
  if (glewInit() != GLEW_OK) {
    glfwDestroyWindow(m_window);
    glfwTerminate();
    throw Error("GLEW cannot initialize the OpenGL context");
  }
#endif
  pinLoadedLibraries();
  m_world = new chai3d::cWorld();
  m_world->m_backgroundColor.setWhite();
  m_camera = new chai3d::cCamera(m_world);
  m_world->addChild(m_camera);
  chai3d::cDirectionalLight* light = new chai3d::cDirectionalLight(m_world);
  m_world->addChild(light);
  light->setEnabled(true);
  light->setDir(-1.0, -0.3, -0.6);
  m_font = chai3d::NEW_CFONT_CALIBRI_20();
  float scale_x = 1.0f, scale_y = 1.0f;
  glfwGetWindowContentScale(m_window, &scale_x, &scale_y);
  m_viewport = new OwnedViewport(m_camera, static_cast<double>(scale_x), static_cast<double>(scale_y));
}

SceneApp::~SceneApp() {
  delete m_viewport;
  delete m_world;  // with its children (camera, light, tool, objects)
  glfwDestroyWindow(m_window);
  glfwTerminate();
}

chai3d::cLabel* SceneApp::addLabel(int a_x, int a_y) {
  chai3d::cLabel* label = new chai3d::cLabel(m_font);
  m_camera->m_frontLayer->addChild(label);
  label->m_fontColor.setBlack();
  label->setLocalPos(a_x, a_y);
  return label;
}

void SceneApp::keyCallback(GLFWwindow* a_window, int a_key, int, int a_action, int) {
  if (a_action != GLFW_PRESS) return;
  auto* app = static_cast<SceneApp*>(glfwGetWindowUserPointer(a_window));
  if (a_key == GLFW_KEY_ESCAPE || a_key == GLFW_KEY_Q) {
    glfwSetWindowShouldClose(a_window, GLFW_TRUE);
  } else if (app->m_keyHandler) {
    app->m_keyHandler(a_key);
  }
}

void SceneApp::renderFrame() {
  int width = 0, height = 0;
  glfwGetFramebufferSize(m_window, &width, &height);
  m_world->updateShadowMaps(false, false);
  m_viewport->renderView(width, height);
  glFinish();
}

bool SceneApp::saveScreenshot() {
  chai3d::cImagePtr image = chai3d::cImage::create();
  m_viewport->copyImageBuffer(image);
  // RGBA from glReadPixels: drop the alpha channel (the window's alpha is meaningless and would
  // make the background transparent). CHAI3D's PNG writer already turns the rows top-down.
  image->convert(GL_RGB);
  if (!image->saveToFile(m_options.screenshot)) {
    std::fprintf(stderr, "uhaptics scene: cannot write the screenshot %s\n", m_options.screenshot.c_str());
    return false;
  }
  std::printf("uhaptics scene: screenshot %s (%d x %d)\n", m_options.screenshot.c_str(), image->getWidth(),
              image->getHeight());
  return true;
}

void SceneApp::run(const std::function<void()>& a_hapticFrame, int a_hapticFramesPerFixedStep,
                   const std::function<void()>& a_graphicsFrame) {
  std::atomic<bool> stop{false};
  std::thread haptics;
  if (!m_options.bounded()) {
    haptics = std::thread([&] {
      while (!stop.load(std::memory_order_relaxed)) a_hapticFrame();
    });
  }
  while (!glfwWindowShouldClose(m_window)) {
    if (m_options.bounded()) {
      for (int i = 0; i < a_hapticFramesPerFixedStep; ++i) a_hapticFrame();
    }
    a_graphicsFrame();
    renderFrame();
    ++m_framesRendered;
    const bool last = m_options.bounded() && m_framesRendered >= m_options.frames;
    if (last && !m_options.screenshot.empty()) saveScreenshot();
    glfwSwapBuffers(m_window);
    glfwPollEvents();
    if (last) break;
  }
  stop = true;
  if (haptics.joinable()) haptics.join();
}

}  // namespace uhaptics::scenes
