// A face's reflectance and emission per pixel, shared by the surface pass
// (scene_gbuffer.frag) and the forward pass (scene_forward.frag).
// TEXTURES is a #define: 0 for a scene with no texture drawn (the faces'
// constant Kd, exactly as before textures existed), 1 otherwise. The scene
// is drawn in ranges of one material; each textured range binds its
// textures and sets these uniforms (Compositor's drawSceneRanges).
#if TEXTURES
in vec2 vUv;                                     // Mesh::texcoords (glTF's convention: v down)
layout(binding = 4) uniform sampler2D uKdTexture;  // sRGB, mipmapped: decoded to linear before filtering
layout(binding = 5) uniform sampler2D uKeTexture;
uniform int uKdMapped;      // 1: Kd = clamp(factor × texture), else the face's constant
uniform vec3 uKdFactor;     // TextureMap::factor
uniform vec4 uKdTransform;  // TextureMap scale (xy) and offset (zw)
uniform int uKeMapped;      // 1: emission scaled by the texture, else uniform
uniform vec3 uKeScale;      // keMap.factor / Ke per channel (0 where Ke is 0): the texture relative to the light's radiance
uniform vec4 uKeTransform;
// A cut-out (Material::alphaMap): the face is absent where factor × its
// coverage (alpha, or an image without alpha's grey level) is below the cut-off.
layout(binding = 8) uniform sampler2D uAlphaTexture;
uniform int uAlphaMapped;     // 1: the range's material has a cut-out
uniform vec4 uAlphaTransform;
uniform float uAlphaFactor;   // TextureMap::factor.r
uniform float uAlphaCutoff;   // Material::alphaCutoff
uniform int uAlphaFromGrey;   // 1: no alpha channel, the grey level is the coverage
#endif

#if TEXTURES
// The mip level each texture read takes, from the fragment's footprint in
// texels (Compositor.h's textureLodShiftFor says why): log2 of its longer
// axis for one pass (the GL's own trilinear choice); for K passes, log2 of
// its shorter axis plus this shift (negative).
uniform float uTextureLodShift;
vec2 gUvDx, gUvDy;  // this fragment's uv derivatives (footprintBegin)
#endif

// Takes the fragment's uv derivatives, first thing in main(): before a
// discard or any branch, where derivatives are defined.
void footprintBegin() {
#if TEXTURES
    gUvDx = dFdx(vUv);
    gUvDy = dFdy(vUv);
#endif
}

#if TEXTURES
// The texture at vUv × transform.xy + transform.zw over the footprint above.
vec4 footprintTexture(sampler2D tex, vec4 transform) {
    vec2 uv = vUv * transform.xy + transform.zw;
#if TEXTURE_ANISOTROPY
    // A GL that filters anisotropically (Compositor's textureAnisotropy),
    // one pass: its own filter over the footprint, as texture() would.
    if (uTextureLodShift >= 0.0) return textureGrad(tex, uv, gUvDx * transform.xy, gUvDy * transform.xy);
#endif
    // The level of the longer axis (one pass) or the shorter (several), in
    // one read: on llvmpipe, no branch, which it would take both ways.
    vec2 texels = vec2(textureSize(tex, 0)) * transform.xy;
    float lx = length(gUvDx * texels), ly = length(gUvDy * texels);
    float axis = uTextureLodShift < 0.0 ? min(lx, ly) : max(lx, ly);
    return textureLod(tex, uv, log2(max(axis, 1e-8)) + uTextureLodShift);
}
#endif

// Whether this fragment falls in a hole of its face's cut-out. (The grey
// level of an image without alpha is read decoded from sRGB here, not as the
// CPU reads it: the same for the black and white masks map_d files hold.)
bool cutAway() {
#if TEXTURES
    if (uAlphaMapped != 0) {
        vec4 t = texture(uAlphaTexture, vUv * uAlphaTransform.xy + uAlphaTransform.zw);
        float coverage = uAlphaFromGrey != 0 ? (t.r + t.g + t.b) / 3.0 : t.a;
        return uAlphaFactor * coverage < uAlphaCutoff;
    }
#endif
    return false;
}

vec3 surfaceKd(vec3 faceKd) {
#if TEXTURES
    if (uKdMapped != 0)
        return clamp(uKdFactor * footprintTexture(uKdTexture, uKdTransform).rgb, 0.0, 1.0);
#endif
    return faceKd;
}

// Emitted radiance here over the light's uniform radiance (Light::radiance).
vec3 emissionScale() {
#if TEXTURES
    if (uKeMapped != 0) return uKeScale * footprintTexture(uKeTexture, uKeTransform).rgb;
#endif
    return vec3(1.0);
}
