// The window: GLFW + OpenGL 3.3 core (libepoxy) + Dear ImGui, and the frame loop that feeds
// mouse and keys to ViewerState, draws it with GlView and the panel, and runs scripts and
// screenshots. All decisions live in ViewerState; this file only wires them to the window.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <fmt/core.h>
#include <imgui.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <thread>

#include "gl_view.h"
#include "panel.h"
#include "script.h"
#include "viewer.h"
#include "viewer_state.h"
#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/io/image.h"
#include "zeroset/io/output_transaction.h"

namespace zeroset::viewer {
namespace {

// The frame loop sleeps to stay at or below this rate, leaving the cores to the simulation
// and the ray caster (with software OpenGL, drawing competes with them for the CPU).
constexpr double kMaxFramesPerSecond = 60;
// Without input or news the live figures in the panel are still refreshed this often.
constexpr double kRefreshPeriodS = 0.25;
// Drawing live results (floaters, improver steps) may take at most this share of the wall
// time: with software OpenGL a frame of ten thousand disks costs as much as a simulation step.
constexpr double kMaxDrawShare = 0.5;
// After an input event ImGui needs a few frames to show its effect (hover, release).
constexpr int kFramesAfterInput = 3;
// How long --wait waits for the mode's work at most.
constexpr double kWaitTimeoutS = 60;
// Fonts of Debian's fonts-dejavu-core; ImGui's built-in font (ASCII only) is the fallback.
constexpr const char* kUiFontPath = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
constexpr const char* kMonoFontPath = "/usr/share/fonts/truetype/dejavu/DejaVuSansMono.ttf";
// Latin-1, Greek, general punctuation, arrows and mathematical operators.
constexpr ImWchar kGlyphRanges[] = {0x0020, 0x00FF, 0x0370, 0x03FF, 0x2000, 0x206F,
                                    0x2190, 0x21FF, 0x2200, 0x22FF, 0};

std::string& glfw_error_text() {
  static std::string text;
  return text;
}

void on_glfw_error(int, const char* description) { glfw_error_text() = description; }

// Time of the last input event (set by GLFW callbacks, which ImGui's own callbacks chain to).
double g_last_input_s = 0;

double now_seconds();

void note_input() { g_last_input_s = now_seconds(); }

// Registers callbacks that note any input; ImGui installs its callbacks afterwards and calls
// these from its own.
void watch_input(GLFWwindow* window) {
  glfwSetCursorPosCallback(window, [](GLFWwindow*, double, double) { note_input(); });
  glfwSetMouseButtonCallback(window, [](GLFWwindow*, int, int, int) { note_input(); });
  glfwSetScrollCallback(window, [](GLFWwindow*, double, double) { note_input(); });
  glfwSetKeyCallback(window, [](GLFWwindow*, int, int, int, int) { note_input(); });
  glfwSetCharCallback(window, [](GLFWwindow*, unsigned int) { note_input(); });
  glfwSetWindowFocusCallback(window, [](GLFWwindow*, int) { note_input(); });
  glfwSetCursorEnterCallback(window, [](GLFWwindow*, int) { note_input(); });
  glfwSetFramebufferSizeCallback(window, [](GLFWwindow*, int, int) { note_input(); });
  glfwSetWindowRefreshCallback(window, [](GLFWwindow*) { note_input(); });
}

double now_seconds() {
  using clock = std::chrono::steady_clock;
  static const clock::time_point start = clock::now();
  return std::chrono::duration<double>(clock::now() - start).count();
}

// GLFW and the window, released in the right order whatever happens.
class Window {
 public:
  Window(int width, int height, const std::string& title) {
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit())
      throw Error(
          fmt::format("cannot open a window: {} (without a display, run under "
                      "xvfb-run)",
                      glfw_error_text()));
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!window_) {
      glfwTerminate();
      throw Error(fmt::format("cannot open an OpenGL 3.3 core window: {}", glfw_error_text()));
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(1);
  }
  ~Window() {
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
  GLFWwindow* get() const { return window_; }

 private:
  GLFWwindow* window_ = nullptr;
};

// The ImGui context with its GLFW and OpenGL 3 backends.
class Gui {
 public:
  Gui(GLFWwindow* window, PanelState& panel) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;  // never write imgui.ini into the user's directory
    if (std::filesystem::exists(kUiFontPath) && std::filesystem::exists(kMonoFontPath)) {
      io.Fonts->AddFontFromFileTTF(kUiFontPath, 15.0f, nullptr, kGlyphRanges);
      panel.mono_font = io.Fonts->AddFontFromFileTTF(kMonoFontPath, 14.0f, nullptr, kGlyphRanges);
    } else {
      io.Fonts->AddFontDefault();
    }
    ImGui::StyleColorsDark();
    ImGuiStyle& style = ImGui::GetStyle();
    style.WindowRounding = 0;
    style.Colors[ImGuiCol_WindowBg].w = 0.94f;
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
  }
  ~Gui() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  Gui(const Gui&) = delete;
  Gui& operator=(const Gui&) = delete;
};

// The back buffer as an image (row 0 at the top).
Image read_framebuffer(int width, int height) {
  std::vector<std::uint8_t> rows(static_cast<size_t>(width) * height * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
  Image image(width, height);
  const size_t stride = static_cast<size_t>(width) * 3;
  for (int y = 0; y < height; ++y)
    std::copy_n(&rows[static_cast<size_t>(height - 1 - y) * stride], stride, image.pixel(0, y));
  return image;
}

class Host : public ScriptHost {
 public:
  Host(GLFWwindow* window, bool& show_ui, bool quiet)
      : window_(window), show_ui_(show_ui), quiet_(quiet) {}
  void save_screenshot(const std::string& path) override {
    if (file_extension(path) != "png")
      throw InvalidArgument("screenshot", path, "the file name must end in .png");
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    write_png(read_framebuffer(w, h), path);
    print(fmt::format("saved {} ({}x{})", path, w, h));
  }
  void set_ui_visible(bool visible) override { show_ui_ = visible; }
  void print(const std::string& line) override {
    if (quiet_) return;
    fmt::print("{}\n", line);
    std::fflush(stdout);
  }

 private:
  GLFWwindow* window_;
  bool& show_ui_;
  bool quiet_;
};

// The typical time a frame takes to draw: the median of the last few, so that a slow first
// frame (software OpenGL compiles its shaders then) or a hiccup does not count.
class DrawTimes {
 public:
  double add(double seconds) {
    recent_[next_++ % recent_.size()] = seconds;
    const size_t n = std::min(next_, recent_.size());
    std::array<double, kCount> sorted = recent_;
    std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.begin() + n);
    return sorted[n / 2];
  }

 private:
  static constexpr size_t kCount = 15;
  std::array<double, kCount> recent_{};
  size_t next_ = 0;
};

// Mouse and keys for the 3D view, when ImGui does not want them.
class Input {
 public:
  void handle(ViewerState& state, PanelState& panel, bool& show_ui, GLFWwindow* window) {
    ImGuiIO& io = ImGui::GetIO();
    const float sx = io.DisplayFramebufferScale.x, sy = io.DisplayFramebufferScale.y;
    for (int b = 0; b < 3; ++b)
      if (ImGui::IsMouseClicked(b)) dragging_[b] = !io.WantCaptureMouse;
    const double dx = io.MouseDelta.x * sx, dy = io.MouseDelta.y * sy;
    const bool moved = dx != 0 || dy != 0;
    if (moved && ImGui::IsMouseDown(0) && dragging_[0]) {
      if (io.KeyShift)
        state.pan(dx, dy);
      else
        state.orbit(dx, dy);
    } else if (moved && ((ImGui::IsMouseDown(1) && dragging_[1]) ||
                         (ImGui::IsMouseDown(2) && dragging_[2]))) {
      state.pan(dx, dy);
    }
    if (!io.WantCaptureMouse && io.MouseWheel != 0) state.zoom(std::pow(0.88, io.MouseWheel));

    if (io.WantCaptureKeyboard) return;
    auto pressed = [](int key) { return ImGui::IsKeyPressed(key, false); };
    if (pressed(GLFW_KEY_R)) state.reset_view();
    if (pressed(GLFW_KEY_SPACE)) {
      if (state.animation().is_playing)
        state.pause();
      else
        state.play();
    }
    if (pressed(GLFW_KEY_1)) state.set_mode(Mode::kFloaters);
    if (pressed(GLFW_KEY_2)) state.set_mode(Mode::kMesh);
    if (pressed(GLFW_KEY_3)) state.set_mode(Mode::kRaytrace);
    DisplaySettings d = state.display();
    if (pressed(GLFW_KEY_W)) {
      d.wireframe = !d.wireframe;
      state.set_display(d);
    }
    if (pressed(GLFW_KEY_P)) {
      d.draw_points = !d.draw_points;
      state.set_display(d);
    }
    if (pressed(GLFW_KEY_S)) {
      d.show_singular = !d.show_singular;
      state.set_display(d);
    }
    if (pressed(GLFW_KEY_H)) show_ui = !show_ui;
    if (pressed(GLFW_KEY_F12)) panel.wants_screenshot = true;
    if (pressed(GLFW_KEY_Q) && io.KeyCtrl) glfwSetWindowShouldClose(window, GLFW_TRUE);
  }

 private:
  bool dragging_[3] = {false, false, false};  // the press began in the 3D view
};

}  // namespace

int run_viewer(const ViewerOptions& options) {
  // Everything the user can get wrong is checked before a window opens.
  if (options.width < 64 || options.height < 64 || options.width > 16384 || options.height > 16384)
    throw InvalidArgument("--size", fmt::format("{}x{}", options.width, options.height),
                          "each side must lie in [64, 16384]");
  if (options.frames < 0)
    throw InvalidArgument("--frames", std::to_string(options.frames), "must be ≥ 0");
  if (!options.screenshot.empty() && file_extension(options.screenshot) != "png")
    throw InvalidArgument("--screenshot", options.screenshot, "the file name must end in .png");
  {
    // Outputs that cannot be written, or that name one file by any spelling, are refused
    // before a window opens; the probe is not committed, so it leaves nothing behind.
    OutputTransaction probe;
    if (!options.screenshot.empty()) probe.declare(options.screenshot, "--screenshot");
    if (!options.stats_out.empty()) probe.declare(options.stats_out, "--stats-out");
  }
  // The last screenshot and the statistics are written as one transaction: both or neither.
  std::optional<OutputTransaction> outputs;
  bool outputs_written = true;
  std::optional<Script> script;
  if (!options.script.empty()) script = Script::load(options.script);
  ViewerState state(options.scene, options.mode, options.threads, options.scene_origin);

  // Mesa's software OpenGL (llvmpipe) draws with one thread per core unless told otherwise;
  // it gets half of them, the floater simulation the other half (ViewerState), so that
  // neither waits for the other. Hardware drivers ignore the variable.
  const std::string gl_threads =
      std::to_string(std::max(1u, std::thread::hardware_concurrency() / 2));
  setenv("LP_NUM_THREADS", gl_threads.c_str(), /*overwrite=*/0);

  const bool is_batch = !options.screenshot.empty() || options.frames > 0;
  const bool is_scripted = script.has_value() || is_batch;
  Window window(options.width, options.height, "zeroset view - " + state.surface().label());
  PanelState panel;
  watch_input(window.get());
  Gui gui(window.get(), panel);
  GlView gl_view;
  bool show_ui = options.show_ui;
  Host host(window.get(), show_ui, options.quiet);
  if (is_scripted) {
    state.set_status_sink(
        [&host](const StatusLine& s) { host.print((s.is_error ? "error: " : "") + s.text); });
    // The surface given on the command line was surveyed before the log existed.
    if (!state.field_warning().empty()) host.print("warning: " + state.field_warning());
  }
  Input input;

  int failures = 0;
  bool is_waiting = options.wait;
  double wait_deadline = -1;
  int frames_left = options.frames > 0 ? options.frames : 60;
  long long frames_drawn = 0;
  const double start_s = now_seconds();

  // Frames are drawn when something changed (input, new results, the end of an animation) or
  // a script needs them, at most kMaxFramesPerSecond a second: with software OpenGL every frame
  // drawn is CPU time the simulation and the ray caster do not get. No exception leaves the
  // loop: actions are guarded inside ViewerState, and input and drawing here.
  int frames_after_input = kFramesAfterInput;
  double last_draw_s = -1;
  DrawTimes draw_times;
  while (!glfwWindowShouldClose(window.get())) {
    const double frame_start = now_seconds();
    glfwPollEvents();
    if (g_last_input_s > last_draw_s) frames_after_input = kFramesAfterInput;
    int fb_w = 0, fb_h = 0, win_w = 0, win_h = 0;
    glfwGetFramebufferSize(window.get(), &fb_w, &fb_h);
    glfwGetWindowSize(window.get(), &win_w, &win_h);
    const double scale = win_w > 0 ? static_cast<double>(fb_w) / win_w : 1.0;
    const int panel_px = show_ui ? static_cast<int>(std::lround(kPanelWidth * scale)) : 0;
    const int view_w = std::max(fb_w - panel_px, 1);
    state.set_viewport(view_w, std::max(fb_h, 1));
    const bool is_new = state.update(frame_start);

    const bool script_running = script && !script->is_finished();
    const bool batch_counting = !script_running && !is_waiting && is_batch;
    const bool must_draw = is_new || frames_after_input > 0 || panel.wants_screenshot ||
                           (script_running && script->needs_frames()) || batch_counting ||
                           frame_start - last_draw_s >= kRefreshPeriodS;
    if (!must_draw) {
      glfwWaitEventsTimeout(1.0 / kMaxFramesPerSecond);
      continue;
    }
    frames_after_input = std::max(frames_after_input - 1, 0);

    const double draw_start = now_seconds();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    state.guard("input", [&] { input.handle(state, panel, show_ui, window.get()); });
    if (show_ui) draw_panel(state, panel, static_cast<float>(win_h));
    ImGui::Render();

    glViewport(0, 0, fb_w, fb_h);
    glClearColor(0.1f, 0.1f, 0.12f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    state.guard("draw", [&] { gl_view.draw(state, panel_px, 0, view_w, fb_h); });
    if (show_ui) ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    ++frames_drawn;
    last_draw_s = frame_start;
    double took = now_seconds() - draw_start;

    // Screenshots read the frame just drawn, before it is swapped away.
    if (panel.wants_screenshot) {
      panel.wants_screenshot = false;
      if (state.guard("screenshot", [&] { host.save_screenshot(panel.screenshot_path); }))
        state.set_status("saved " + panel.screenshot_path);
    }
    bool is_done = false;
    if (script_running) {
      script->advance(state, host, frame_start);
    } else if (is_waiting) {
      if (wait_deadline < 0) wait_deadline = frame_start + kWaitTimeoutS;
      if (state.is_settled()) {
        is_waiting = false;
      } else if (frame_start > wait_deadline) {
        host.print("error: --wait: the view did not settle in time");
        ++failures;
        is_waiting = false;
      }
    } else if (is_batch) {
      if (--frames_left <= 0) {
        if (!options.screenshot.empty()) {
          outputs.emplace();
          if (!state.guard("screenshot", [&] { host.save_screenshot(options.screenshot); })) {
            ++failures;
            outputs_written = false;
          }
        }
        is_done = true;
      }
    } else if (script) {
      is_done = true;  // the script ended and nothing else was asked for
    }
    const double swap_start = now_seconds();
    glfwSwapBuffers(window.get());
    if (is_done) break;
    // The swap waits for software OpenGL to finish the frame: it is part of the drawing's
    // cost (screenshots and script commands in between are not).
    took += now_seconds() - swap_start;
    const double draw_seconds = draw_times.add(took);
    state.frame_drawn(frame_start, draw_seconds);
    state.set_live_frame_interval(draw_seconds / kMaxDrawShare);

    const double rest = 1.0 / kMaxFramesPerSecond - (now_seconds() - frame_start);
    if (rest > 0) std::this_thread::sleep_for(std::chrono::duration<double>(rest));
  }

  if (script) failures += script->failures();
  if (!options.stats_out.empty() && outputs_written) {
    if (!outputs) outputs.emplace();
    nlohmann::json j = state.stats().to_json();
    j["frames"] = frames_drawn;
    j["seconds"] = now_seconds() - start_s;
    j["failures"] = failures;
    if (!state.guard("stats", [&] {
          const std::string text = j.dump(2) + "\n";
          write_file_atomically(options.stats_out, [&](std::ostream& out) { out << text; });
        })) {
      ++failures;
      outputs_written = false;
    }
  }
  if (outputs && outputs_written && !state.guard("outputs", [&] { outputs->commit(); })) ++failures;
  return failures > 0 ? 1 : 0;
}

}  // namespace zeroset::viewer
