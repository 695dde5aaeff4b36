// Small RAII owners of GL objects, bound to the GlApi they were made with.
#pragma once

#include "GlApi.h"

#include <glm/glm.hpp>
#include <string>
#include <utility>
#include <vector>

namespace ml {

// Owns one GL name; `Deleter` calls the right glDelete*.
template <void (*Delete)(const GlApi&, GLuint)>
class GlName {
public:
    GlName() = default;
    GlName(const GlApi& gl, GLuint name) : gl_(&gl), name_(name) {}
    GlName(GlName&& o) noexcept : gl_(o.gl_), name_(std::exchange(o.name_, 0)) {}
    GlName& operator=(GlName&& o) noexcept {
        if (this != &o) {
            reset();
            gl_ = o.gl_;
            name_ = std::exchange(o.name_, 0);
        }
        return *this;
    }
    ~GlName() { reset(); }
    GLuint id() const { return name_; }
    explicit operator bool() const { return name_ != 0; }
    void reset() {
        if (name_) Delete(*gl_, name_);
        name_ = 0;
    }

private:
    const GlApi* gl_ = nullptr;
    GLuint name_ = 0;
};

namespace gldelete {
inline void buffer(const GlApi& gl, GLuint n) { gl.DeleteBuffers(1, &n); }
inline void vertexArray(const GlApi& gl, GLuint n) { gl.DeleteVertexArrays(1, &n); }
inline void texture(const GlApi& gl, GLuint n) { gl.DeleteTextures(1, &n); }
inline void framebuffer(const GlApi& gl, GLuint n) { gl.DeleteFramebuffers(1, &n); }
inline void query(const GlApi& gl, GLuint n) { gl.DeleteQueries(1, &n); }
inline void program(const GlApi& gl, GLuint n) { gl.DeleteProgram(n); }
}  // namespace gldelete

using GlBuffer = GlName<gldelete::buffer>;
using GlVertexArray = GlName<gldelete::vertexArray>;
using GlTexture = GlName<gldelete::texture>;
using GlFramebuffer = GlName<gldelete::framebuffer>;
using GlQuery = GlName<gldelete::query>;

GlBuffer makeBuffer(const GlApi& gl, size_t bytes, const void* data, GLenum usage = GL_STATIC_DRAW);
GlVertexArray makeVertexArray(const GlApi& gl);
GlTexture makeTexture2D(const GlApi& gl, GLenum internalFormat, int width, int height);
GlQuery makeQuery(const GlApi& gl, GLenum target);
// A framebuffer with these colour attachments (in order) and depth texture
// (0: none); throws std::runtime_error naming `what` if incomplete.
GlFramebuffer makeFramebuffer(const GlApi& gl, std::initializer_list<GLuint> colors, GLuint depth, const char* what);

// A linked program. Compile and link errors throw std::runtime_error with the
// shader's name and the driver's log.
class GlProgram {
public:
    struct Stage {
        GLenum type;         // GL_VERTEX_SHADER, ...
        const char* name;    // for messages, e.g. "direct_coverage.vert"
        std::string source;  // full GLSL source including #version
    };
    GlProgram() = default;
    GlProgram(const GlApi& gl, const std::vector<Stage>& stages);

    GLuint id() const { return program_.id(); }
    void use() const;
    // Location of a uniform; -1 (ignored by glUniform*) when the compiler removed it.
    GLint uniform(const char* name) const;

private:
    const GlApi* gl_ = nullptr;
    GlName<gldelete::program> program_;
};

// Prepends `#version 450 core` and the given shared snippets to a shader body.
std::string glslSource(std::initializer_list<const char*> parts);

}  // namespace ml
