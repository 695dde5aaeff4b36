// The OpenGL 4.5 core functions Meshlight uses, loaded per context through
// that context's own getProcAddress.
//
// Why not libepoxy or GLEW: both fail on OSMesa on Debian 12, and linking
// -lGL beside -lOSMesa silently picks the wrong dispatch. A table per context
// (passed explicitly as `gl`) keeps every call tied to the context it was
// loaded from, which also holds when the viewer's window and the worker's
// headless context live in one process.
#pragma once

#include <GL/glcorearb.h>

#include <functional>
#include <string>

namespace ml {

// X(type, name): `name` is the GL name without the "gl" prefix.
#define ML_GL_FUNCTIONS(X)                                              \
    X(PFNGLGETERRORPROC, GetError)                                      \
    X(PFNGLGETSTRINGPROC, GetString)                                    \
    X(PFNGLGETSTRINGIPROC, GetStringi)                                  \
    X(PFNGLGETINTEGERVPROC, GetIntegerv)                                \
    X(PFNGLENABLEPROC, Enable)                                          \
    X(PFNGLDISABLEPROC, Disable)                                        \
    X(PFNGLFINISHPROC, Finish)                                          \
    X(PFNGLFLUSHPROC, Flush)                                            \
    X(PFNGLVIEWPORTPROC, Viewport)                                      \
    X(PFNGLSCISSORPROC, Scissor)                                        \
    X(PFNGLCLEARPROC, Clear)                                            \
    X(PFNGLCLEARCOLORPROC, ClearColor)                                  \
    X(PFNGLCLEARDEPTHPROC, ClearDepth)                                  \
    X(PFNGLCLEARBUFFERUIVPROC, ClearBufferuiv)                          \
    X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv)                            \
    X(PFNGLCLEARBUFFERFIPROC, ClearBufferfi)                            \
    X(PFNGLSTENCILFUNCPROC, StencilFunc)                                \
    X(PFNGLSTENCILOPPROC, StencilOp)                                    \
    X(PFNGLSTENCILMASKPROC, StencilMask)                                \
    X(PFNGLDEPTHFUNCPROC, DepthFunc)                                    \
    X(PFNGLDEPTHMASKPROC, DepthMask)                                    \
    X(PFNGLCOLORMASKIPROC, ColorMaski)                                  \
    X(PFNGLLOGICOPPROC, LogicOp)                                        \
    X(PFNGLCULLFACEPROC, CullFace)                                      \
    X(PFNGLFRONTFACEPROC, FrontFace)                                    \
    X(PFNGLCLIPCONTROLPROC, ClipControl)                                \
    X(PFNGLBLENDFUNCPROC, BlendFunc)                                    \
    X(PFNGLBLENDEQUATIONPROC, BlendEquation)                            \
    X(PFNGLBINDTEXTUREUNITPROC, BindTextureUnit)                        \
    X(PFNGLPOLYGONOFFSETPROC, PolygonOffset)                            \
    X(PFNGLREADPIXELSPROC, ReadPixels)                                  \
    X(PFNGLREADBUFFERPROC, ReadBuffer)                                  \
    X(PFNGLDRAWBUFFERSPROC, DrawBuffers)                                \
    X(PFNGLPIXELSTOREIPROC, PixelStorei)                                \
    X(PFNGLCREATESHADERPROC, CreateShader)                              \
    X(PFNGLSHADERSOURCEPROC, ShaderSource)                              \
    X(PFNGLCOMPILESHADERPROC, CompileShader)                            \
    X(PFNGLGETSHADERIVPROC, GetShaderiv)                                \
    X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                      \
    X(PFNGLDELETESHADERPROC, DeleteShader)                              \
    X(PFNGLCREATEPROGRAMPROC, CreateProgram)                            \
    X(PFNGLATTACHSHADERPROC, AttachShader)                              \
    X(PFNGLLINKPROGRAMPROC, LinkProgram)                                \
    X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                              \
    X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                    \
    X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                            \
    X(PFNGLUSEPROGRAMPROC, UseProgram)                                  \
    X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)                  \
    X(PFNGLUNIFORM1IPROC, Uniform1i)                                    \
    X(PFNGLUNIFORM1UIPROC, Uniform1ui)                                  \
    X(PFNGLUNIFORM1FPROC, Uniform1f)                                    \
    X(PFNGLUNIFORM2FPROC, Uniform2f)                                    \
    X(PFNGLUNIFORM2IPROC, Uniform2i)                                    \
    X(PFNGLUNIFORM3FPROC, Uniform3f)                                    \
    X(PFNGLUNIFORM4FPROC, Uniform4f)                                    \
    X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)                      \
    X(PFNGLCREATEBUFFERSPROC, CreateBuffers)                            \
    X(PFNGLNAMEDBUFFERDATAPROC, NamedBufferData)                        \
    X(PFNGLNAMEDBUFFERSUBDATAPROC, NamedBufferSubData)                  \
    X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                            \
    X(PFNGLBINDBUFFERPROC, BindBuffer)                                  \
    X(PFNGLCREATEVERTEXARRAYSPROC, CreateVertexArrays)                  \
    X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                  \
    X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                        \
    X(PFNGLVERTEXARRAYVERTEXBUFFERPROC, VertexArrayVertexBuffer)        \
    X(PFNGLVERTEXARRAYELEMENTBUFFERPROC, VertexArrayElementBuffer)      \
    X(PFNGLENABLEVERTEXARRAYATTRIBPROC, EnableVertexArrayAttrib)        \
    X(PFNGLVERTEXARRAYATTRIBFORMATPROC, VertexArrayAttribFormat)        \
    X(PFNGLVERTEXARRAYATTRIBIFORMATPROC, VertexArrayAttribIFormat)      \
    X(PFNGLVERTEXARRAYATTRIBBINDINGPROC, VertexArrayAttribBinding)      \
    X(PFNGLCREATETEXTURESPROC, CreateTextures)                          \
    X(PFNGLTEXTURESTORAGE2DPROC, TextureStorage2D)                      \
    X(PFNGLTEXTUREPARAMETERIPROC, TextureParameteri)                    \
    X(PFNGLTEXTURESUBIMAGE2DPROC, TextureSubImage2D)                    \
    X(PFNGLGENERATETEXTUREMIPMAPPROC, GenerateTextureMipmap)            \
    X(PFNGLDELETETEXTURESPROC, DeleteTextures)                          \
    X(PFNGLCREATEFRAMEBUFFERSPROC, CreateFramebuffers)                  \
    X(PFNGLNAMEDFRAMEBUFFERTEXTUREPROC, NamedFramebufferTexture)        \
    X(PFNGLNAMEDFRAMEBUFFERDRAWBUFFERSPROC, NamedFramebufferDrawBuffers) \
    X(PFNGLNAMEDFRAMEBUFFERREADBUFFERPROC, NamedFramebufferReadBuffer)  \
    X(PFNGLCHECKNAMEDFRAMEBUFFERSTATUSPROC, CheckNamedFramebufferStatus) \
    X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                  \
    X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                        \
    X(PFNGLBLITNAMEDFRAMEBUFFERPROC, BlitNamedFramebuffer)              \
    X(PFNGLDRAWARRAYSPROC, DrawArrays)                                  \
    X(PFNGLDRAWELEMENTSPROC, DrawElements)                              \
    X(PFNGLMULTIDRAWARRAYSPROC, MultiDrawArrays)                        \
    X(PFNGLCREATEQUERIESPROC, CreateQueries)                            \
    X(PFNGLDELETEQUERIESPROC, DeleteQueries)                            \
    X(PFNGLBEGINQUERYPROC, BeginQuery)                                  \
    X(PFNGLENDQUERYPROC, EndQuery)                                      \
    X(PFNGLGETQUERYOBJECTUIVPROC, GetQueryObjectuiv)                    \
    X(PFNGLDISPATCHCOMPUTEPROC, DispatchCompute)                        \
    X(PFNGLMEMORYBARRIERPROC, MemoryBarrier)                            \
    X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                          \
    X(PFNGLBINDIMAGETEXTUREPROC, BindImageTexture)                      \
    X(PFNGLGETNAMEDBUFFERSUBDATAPROC, GetNamedBufferSubData)            \
    X(PFNGLGETTEXTUREIMAGEPROC, GetTextureImage)                        \
    X(PFNGLTEXTURESTORAGE3DPROC, TextureStorage3D)                      \
    X(PFNGLTEXTURESUBIMAGE3DPROC, TextureSubImage3D)                    \
    X(PFNGLCOPYIMAGESUBDATAPROC, CopyImageSubData)                      \
    X(PFNGLDRAWARRAYSINSTANCEDBASEINSTANCEPROC, DrawArraysInstancedBaseInstance) \
    X(PFNGLUNIFORM3IPROC, Uniform3i)                                    \
    X(PFNGLUNIFORMMATRIX3FVPROC, UniformMatrix3fv)

struct GlApi {
#define ML_GL_DECLARE(type, name) type name = nullptr;
    ML_GL_FUNCTIONS(ML_GL_DECLARE)
#undef ML_GL_DECLARE

    int majorVersion = 0;
    int minorVersion = 0;
    std::string renderer;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"

    // Loads every function through `getProcAddress` (the current context's),
    // then checks that the context really is 4.5 core or newer: OSMesa returns
    // non-null for names it does not know, so non-null proves nothing.
    // Throws std::runtime_error naming what is missing.
    void load(const std::function<void*(const char*)>& getProcAddress);

    bool hasExtension(const char* name) const;
};

// Throws std::runtime_error("<what>: GL error 0x0502 (GL_INVALID_OPERATION)")
// when glGetError reports one; a cheap check placed after each pass.
void checkGl(const GlApi& gl, const char* what);

}  // namespace ml
