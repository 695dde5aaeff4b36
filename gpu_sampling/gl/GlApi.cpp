#include "GlApi.h"

#include <cstring>
#include <stdexcept>
#include <string>

namespace ml {

void GlApi::load(const std::function<void*(const char*)>& getProcAddress) {
    std::string missing;
#define ML_GL_LOAD(type, name)                                          \
    name = reinterpret_cast<type>(getProcAddress("gl" #name));          \
    if (!name) missing += " gl" #name;
    ML_GL_FUNCTIONS(ML_GL_LOAD)
#undef ML_GL_LOAD
    if (!missing.empty()) throw std::runtime_error("OpenGL functions not found:" + missing);

    GetIntegerv(GL_MAJOR_VERSION, &majorVersion);
    GetIntegerv(GL_MINOR_VERSION, &minorVersion);
    const char* r = reinterpret_cast<const char*>(GetString(GL_RENDERER));
    renderer = r ? r : "unknown";
    if (majorVersion * 10 + minorVersion < 45)
        throw std::runtime_error("OpenGL 4.5 core is required, the context offers " +
                                 std::to_string(majorVersion) + "." + std::to_string(minorVersion) +
                                 " (" + renderer + ")");
    // Drain errors left by context creation so the first pass's check is ours.
    while (GetError() != GL_NO_ERROR) {}
}

bool GlApi::hasExtension(const char* name) const {
    GLint n = 0;
    GetIntegerv(GL_NUM_EXTENSIONS, &n);
    for (GLint i = 0; i < n; ++i)
        if (std::strcmp(reinterpret_cast<const char*>(GetStringi(GL_EXTENSIONS, GLuint(i))), name) == 0)
            return true;
    return false;
}

void checkGl(const GlApi& gl, const char* what) {
    const GLenum e = gl.GetError();
    if (e == GL_NO_ERROR) return;
    const char* name = "unknown";
    switch (e) {
        case GL_INVALID_ENUM: name = "GL_INVALID_ENUM"; break;
        case GL_INVALID_VALUE: name = "GL_INVALID_VALUE"; break;
        case GL_INVALID_OPERATION: name = "GL_INVALID_OPERATION"; break;
        case GL_INVALID_FRAMEBUFFER_OPERATION: name = "GL_INVALID_FRAMEBUFFER_OPERATION"; break;
        case GL_OUT_OF_MEMORY: name = "GL_OUT_OF_MEMORY"; break;
        default: break;
    }
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", e);
    throw std::runtime_error(std::string(what) + ": GL error " + code + " (" + name + ")");
}

}  // namespace ml
