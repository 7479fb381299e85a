#include "Window.h"

#include <glad/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <cstring>
#include <optional>

namespace ff::viewer {

namespace {

std::string lastGlfwError() {
    const char* description = nullptr;
    if (glfwGetError(&description) == GLFW_NO_ERROR || !description)
        return "unknown GLFW error";
    return description;
}

std::optional<Key> toKey(int glfwKey) {
    switch (glfwKey) {
    case GLFW_KEY_W:
        return Key::W;
    case GLFW_KEY_A:
        return Key::A;
    case GLFW_KEY_S:
        return Key::S;
    case GLFW_KEY_D:
        return Key::D;
    case GLFW_KEY_Q:
        return Key::Q;
    case GLFW_KEY_E:
        return Key::E;
    case GLFW_KEY_LEFT_SHIFT:
    case GLFW_KEY_RIGHT_SHIFT:
        return Key::Shift;
    case GLFW_KEY_TAB:
        return Key::Tab;
    case GLFW_KEY_R:
        return Key::R;
    case GLFW_KEY_M:
        return Key::M;
    case GLFW_KEY_H:
        return Key::H;
    case GLFW_KEY_P:
        return Key::P;
    case GLFW_KEY_F12:
        return Key::F12;
    case GLFW_KEY_ESCAPE:
        return Key::Escape;
    case GLFW_KEY_LEFT_BRACKET:
        return Key::LeftBracket;
    case GLFW_KEY_RIGHT_BRACKET:
        return Key::RightBracket;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
        return Key::Minus;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
        return Key::Equal;
    default:
        return std::nullopt;
    }
}

} // namespace

struct Window::Impl {
    GLFWwindow* window = nullptr;
    InputState input;
    std::array<bool, 3> buttons{}; ///< left, right, middle held
    std::optional<glm::dvec2> cursor;

    ~Impl() {
        if (window)
            glfwDestroyWindow(window);
        glfwTerminate();
    }

    static Impl& of(GLFWwindow* window) {
        return *static_cast<Impl*>(glfwGetWindowUserPointer(window));
    }

    static void onKey(GLFWwindow* window, int key, int /*scancode*/, int action, int /*mods*/) {
        const std::optional<Key> k = toKey(key);
        if (!k)
            return;
        InputState& in = of(window).input;
        const auto i = static_cast<std::size_t>(*k);
        in.down[i] = action != GLFW_RELEASE;
        if (action != GLFW_RELEASE)
            ++in.presses[i];
    }

    static void onButton(GLFWwindow* window, int button, int action, int /*mods*/) {
        if (button >= 0 && button < 3)
            of(window).buttons[static_cast<std::size_t>(button)] = action == GLFW_PRESS;
    }

    static void onCursor(GLFWwindow* window, double x, double y) {
        Impl& s = of(window);
        const glm::dvec2 position(x, y);
        if (s.cursor) {
            const glm::dvec2 delta = position - *s.cursor;
            if (s.buttons[GLFW_MOUSE_BUTTON_LEFT])
                s.input.leftDrag += delta;
            if (s.buttons[GLFW_MOUSE_BUTTON_RIGHT])
                s.input.rightDrag += delta;
            if (s.buttons[GLFW_MOUSE_BUTTON_MIDDLE])
                s.input.middleDrag += delta;
        }
        s.cursor = position;
    }

    static void onScroll(GLFWwindow* window, double /*x*/, double y) {
        of(window).input.scroll += y;
    }
};

Window::Window(std::unique_ptr<Impl> impl)
    : mImpl(std::move(impl)) {}
Window::~Window() = default;

Result<std::unique_ptr<Window>> Window::create(const WindowOptions& options) {
    if (!glfwInit())
        return Status(
                ErrorCode::Unsupported,
                "cannot open a window (is DISPLAY set?): " + lastGlfwError());
    auto impl = std::make_unique<Impl>(); // from here on, its destructor terminates GLFW
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_RESIZABLE, options.resizable ? GLFW_TRUE : GLFW_FALSE);
    glfwWindowHint(GLFW_DEPTH_BITS, 0); // the renderer draws into its own target
    glfwWindowHint(GLFW_STENCIL_BITS, 0);
    glfwWindowHint(GLFW_SAMPLES, 0); // a multisampled window could not be blitted to
    impl->window = glfwCreateWindow(
            options.width, options.height, options.title.c_str(), nullptr, nullptr);
    if (!impl->window)
        return Status(
                ErrorCode::Unsupported,
                "cannot create a window with an OpenGL 4.5 core context: " + lastGlfwError());
    glfwMakeContextCurrent(impl->window);
    const int version = gladLoadGL(glfwGetProcAddress);
    if (GLAD_VERSION_MAJOR(version) * 10 + GLAD_VERSION_MINOR(version) < 45)
        return Status(
                ErrorCode::Unsupported, "the window's context does not provide OpenGL 4.5 core");
    glfwSwapInterval(options.vsync ? 1 : 0);
    glfwSetWindowUserPointer(impl->window, impl.get());
    glfwSetKeyCallback(impl->window, &Impl::onKey);
    glfwSetMouseButtonCallback(impl->window, &Impl::onButton);
    glfwSetCursorPosCallback(impl->window, &Impl::onCursor);
    glfwSetScrollCallback(impl->window, &Impl::onScroll);
    return std::unique_ptr<Window>(new Window(std::move(impl)));
}

namespace {

void clearEvents(InputState& in) {
    in.presses.fill(0);
    in.leftDrag = in.rightDrag = in.middleDrag = glm::dvec2(0.0);
    in.scroll = 0.0;
}

} // namespace

const InputState& Window::poll() {
    clearEvents(mImpl->input);
    glfwPollEvents();
    return mImpl->input;
}

const InputState& Window::wait() {
    clearEvents(mImpl->input);
    glfwWaitEvents();
    return mImpl->input;
}

bool Window::shouldClose() const {
    return glfwWindowShouldClose(mImpl->window) != 0;
}

void Window::requestClose() {
    glfwSetWindowShouldClose(mImpl->window, GLFW_TRUE);
}

glm::ivec2 Window::framebufferSize() const {
    glm::ivec2 size(0);
    glfwGetFramebufferSize(mImpl->window, &size.x, &size.y);
    return size;
}

void Window::swapBuffers() {
    glfwSwapBuffers(mImpl->window);
}

void Window::setTitle(const std::string& title) {
    glfwSetWindowTitle(mImpl->window, title.c_str());
}

runtime::Image Window::readBackBuffer() const {
    const glm::ivec2 size = framebufferSize();
    runtime::Image image;
    image.width = size.x;
    image.height = size.y;
    const auto rowBytes = static_cast<std::size_t>(size.x) * 4;
    std::vector<std::uint8_t> rows(rowBytes * static_cast<std::size_t>(size.y));
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, size.x, size.y, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
    image.rgba.resize(rows.size());
    for (int y = 0; y < size.y; ++y) // GL rows run bottom-up
        std::memcpy(
                image.pixel(0, size.y - 1 - y),
                rows.data() + static_cast<std::size_t>(y) * rowBytes,
                rowBytes);
    for (std::size_t i = 3; i < image.rgba.size(); i += 4)
        image.rgba[i] = 255; // the window is opaque whatever its alpha bits hold
    return image;
}

std::string Window::description() const {
    const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    return std::string(version ? version : "?") + " / " + (renderer ? renderer : "?");
}

} // namespace ff::viewer
