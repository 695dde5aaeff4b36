#include "GlObjects.h"

#include <stdexcept>

namespace ml {

GlBuffer makeBuffer(const GlApi& gl, size_t bytes, const void* data, GLenum usage) {
    GLuint n = 0;
    gl.CreateBuffers(1, &n);
    gl.NamedBufferData(n, GLsizeiptr(bytes), data, usage);
    return GlBuffer(gl, n);
}

GlVertexArray makeVertexArray(const GlApi& gl) {
    GLuint n = 0;
    gl.CreateVertexArrays(1, &n);
    return GlVertexArray(gl, n);
}

GlTexture makeTexture2D(const GlApi& gl, GLenum internalFormat, int width, int height) {
    GLuint n = 0;
    gl.CreateTextures(GL_TEXTURE_2D, 1, &n);
    gl.TextureStorage2D(n, 1, internalFormat, width, height);
    gl.TextureParameteri(n, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl.TextureParameteri(n, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return GlTexture(gl, n);
}

GlFramebuffer makeFramebuffer(const GlApi& gl, std::initializer_list<GLuint> colors, GLuint depth, const char* what) {
    GLuint f = 0;
    gl.CreateFramebuffers(1, &f);
    GlFramebuffer fb(gl, f);
    std::vector<GLenum> buffers;
    for (GLuint c : colors) {
        const GLenum att = GLenum(GL_COLOR_ATTACHMENT0 + buffers.size());
        gl.NamedFramebufferTexture(f, att, c, 0);
        buffers.push_back(att);
    }
    if (depth) gl.NamedFramebufferTexture(f, GL_DEPTH_ATTACHMENT, depth, 0);
    gl.NamedFramebufferDrawBuffers(f, GLsizei(buffers.size()), buffers.data());
    if (gl.CheckNamedFramebufferStatus(f, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw std::runtime_error(std::string(what) + ": framebuffer incomplete");
    return fb;
}

GlQuery makeQuery(const GlApi& gl, GLenum target) {
    GLuint n = 0;
    gl.CreateQueries(target, 1, &n);
    return GlQuery(gl, n);
}

namespace {

// The driver's log of a shader or program.
template <typename GetIv, typename GetLog>
std::string infoLog(GLuint object, GetIv getiv, GetLog getLog) {
    GLint len = 0;
    getiv(object, GL_INFO_LOG_LENGTH, &len);
    std::string log(size_t(std::max(len, 1)), '\0');
    getLog(object, len, nullptr, log.data());
    return log;
}

GLuint compile(const GlApi& gl, const GlProgram::Stage& s) {
    const GLuint sh = gl.CreateShader(s.type);
    const char* src = s.source.c_str();
    gl.ShaderSource(sh, 1, &src, nullptr);
    gl.CompileShader(sh);
    GLint ok = 0;
    gl.GetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        const std::string log = infoLog(sh, gl.GetShaderiv, gl.GetShaderInfoLog);
        gl.DeleteShader(sh);
        throw std::runtime_error(std::string("shader ") + s.name + " does not compile:\n" + log);
    }
    return sh;
}

}  // namespace

GlProgram::GlProgram(const GlApi& gl, const std::vector<Stage>& stages) : gl_(&gl) {
    const GLuint p = gl.CreateProgram();
    program_ = GlName<gldelete::program>(gl, p);
    std::vector<GLuint> shaders;
    std::string names;
    for (const Stage& s : stages) {
        shaders.push_back(compile(gl, s));
        gl.AttachShader(p, shaders.back());
        names += std::string(names.empty() ? "" : " + ") + s.name;
    }
    gl.LinkProgram(p);
    for (GLuint s : shaders) gl.DeleteShader(s);  // flagged; freed with the program
    GLint ok = 0;
    gl.GetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) throw std::runtime_error("program " + names + " does not link:\n" + infoLog(p, gl.GetProgramiv, gl.GetProgramInfoLog));
}

void GlProgram::use() const { gl_->UseProgram(program_.id()); }

GLint GlProgram::uniform(const char* name) const { return gl_->GetUniformLocation(program_.id(), name); }

std::string glslSource(std::initializer_list<const char*> parts) {
    std::string s = "#version 450 core\n";
    for (const char* p : parts) s += p;
    return s;
}

}  // namespace ml
