#pragma once

#include <ff/runtime/Image.h>
#include <ff/storage/Status.h>

#include <glm/glm.hpp>

#include <array>
#include <cstddef>
#include <memory>
#include <string>

namespace ff::viewer {

/** The keys the viewer reacts to (GLFW's key codes stay inside Window.cpp). */
enum class Key : std::size_t {
    W,
    A,
    S,
    D,
    Q,
    E,
    Shift,
    Tab,
    R,
    M,
    H,
    P,
    F12,
    Escape,
    LeftBracket,
    RightBracket,
    Minus,
    Equal,
    Count,
};

/** Input gathered between two Window::poll() calls. Pixels are framebuffer-independent screen
 *  coordinates, y down. */
struct InputState {
    std::array<bool, static_cast<std::size_t>(Key::Count)> down{};   ///< held now
    std::array<int, static_cast<std::size_t>(Key::Count)> presses{}; ///< presses (and repeats)
    glm::dvec2 leftDrag{0.0};   ///< cursor motion while the left button was held
    glm::dvec2 rightDrag{0.0};  ///< ... right button
    glm::dvec2 middleDrag{0.0}; ///< ... middle button
    double scroll = 0.0;        ///< wheel notches, positive away from the user

    bool isDown(Key k) const { return down[static_cast<std::size_t>(k)]; }
    int pressed(Key k) const { return presses[static_cast<std::size_t>(k)]; }
};

struct WindowOptions {
    int width = 1280;
    int height = 720;
    std::string title = "farfield";
    bool resizable = true;
    bool vsync = true;
};

/**
 * A GLFW window with a current OpenGL 4.5 core context whose functions are loaded into glad
 * (gladLoadGL(glfwGetProcAddress)), so runtime::Renderer draws into it. GLFW is process-global:
 * one Window at a time, created and used on the main thread only.
 */
class Window {
public:
    /** Errors: Unsupported when there is no display or no OpenGL 4.5 core context. */
    [[nodiscard]] static Result<std::unique_ptr<Window>> create(const WindowOptions& options);
    ~Window();
    Window(const Window&) = delete;
    Window& operator=(const Window&) = delete;

    /** Processes window events; returns what happened since the last poll(). */
    const InputState& poll();
    /** As poll(), but sleeps until an event arrives (e.g. while minimized). */
    const InputState& wait();
    bool shouldClose() const;
    void requestClose();
    /** Size of the default framebuffer in pixels (0 x 0 while minimized). */
    glm::ivec2 framebufferSize() const;
    void swapBuffers();
    void setTitle(const std::string& title);

    /**
     * Reads the back buffer (framebuffer 0) into an image: sRGB8 bytes as displayed, top row
     * first, alpha 255. Call before swapBuffers().
     */
    [[nodiscard]] runtime::Image readBackBuffer() const;

    /** "4.5 (Core Profile) Mesa 22.3.6 / llvmpipe (...)" */
    std::string description() const;

private:
    struct Impl;
    explicit Window(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> mImpl;
};

} // namespace ff::viewer
