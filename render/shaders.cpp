// The GLSL sources of the renderer's programs (see shaders.h).
#include "render/shaders.h"

namespace springy::render {

const char* const kMeshVs = R"(#version 330 core
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
uniform mat4 uViewProj;
invariant gl_Position;  // the ground is drawn by two variants and must land on the same depths
uniform mat4 uLightViewProj;
uniform float uNormalOffset;
out vec3 vPos;
out vec3 vNormal;
out vec4 vLightPos;
out vec4 vLightPosBack;
void main() {
  vPos = aPos;
  vNormal = aNormal;
  // Normal offset: look the shadow map up slightly off the surface (less acne), on the side
  // being shaded: the front's (along the normal) or, for a back face, the back's. A cloth lit
  // from behind would otherwise look its shadow up inside its own shadow, in stripes.
  vLightPos = uLightViewProj * vec4(aPos + aNormal * uNormalOffset, 1.0);
  vLightPosBack = uLightViewProj * vec4(aPos - aNormal * uNormalOffset, 1.0);
  gl_Position = uViewProj * vec4(aPos, 1.0);
}
)";

// The look shared by every shaded pixel and by toneCurveOnGpu (look.h): the sRGB transfer
// functions (IEC 61966-2-1) and the tone curve. The curve is the highlight shoulder of Khronos
// PBR Neutral (Khronos 3D Commerce, "PBR Neutral Specification", 2024): identity below a knee,
// above it the peak channel is compressed as newPeak = 1 - d^2 / (peak + d - knee), d = 1 - knee
// (value and slope continuous at the knee), every channel scaled by newPeak / peak (hue kept)
// and mixed towards white by g = 1 - 1 / (0.15 (peak - newPeak) + 1). Two deviations, both so
// that the colours a scene names come out as named: the knee is 0.9 (PBR Neutral: 0.76), above
// the brightest documented sky colour (0.95 display = 0.89 linear), and there is no 0.04
// black offset (PBR Neutral removes the F0 reflection every one of its surfaces adds; ours add
// none). What it changes: a highlight that used to clip per channel (a pink's highlight turned
// yellow-white at 1.0 red) now rolls off towards white with its hue.
const char* const kLookGlsl = R"(
vec3 srgbEncode(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
vec3 toneMap(vec3 c) {
  const float knee = 0.9;
  const float d = 1.0 - knee;
  c = max(c, vec3(0.0));
  float peak = max(c.r, max(c.g, c.b));
  if (peak < knee) return c;
  float newPeak = 1.0 - d * d / (peak + d - knee);
  c *= newPeak / peak;
  float g = 1.0 - 1.0 / (0.15 * (peak - newPeak) + 1.0);
  return mix(c, vec3(newPeak), g);
}
vec3 toDisplay(vec3 c) { return srgbEncode(toneMap(c)); }
)";

// Compiled in variants (see meshVariantSource): SHADOWS, GROUND, FLAT, JELLY and CONTACT are preprocessor
// switches, so a fragment only runs the code its mesh needs (llvmpipe executes both sides of a
// branch, even on a uniform).
namespace {
constexpr const char* kMeshFsBody = R"(
in vec3 vPos;
in vec3 vNormal;
in vec4 vLightPos;
in vec4 vLightPosBack;
uniform vec3 uAlbedo;       // linear colour (ground: colour A)
uniform float uAlpha;
uniform float uShininess;
uniform float uSpecular;
uniform vec3 uToLight;      // unit vector towards the light
uniform vec3 uLightColour;
uniform vec3 uAmbientSky;   // hemisphere ambient: linear light from straight above ...
uniform vec3 uAmbientGround;  // ... and from straight below
uniform vec3 uEye;
uniform sampler2DShadow uShadowMap;
uniform float uShadowStep;  // PCF tap spacing, shadow-map uv units
uniform vec3 uGroundOrigin;
uniform vec3 uGroundU;
uniform vec3 uGroundV;
uniform vec3 uGroundB;      // linear colour B
uniform float uTile;
uniform float uGroundExtent;
uniform vec3 uSkyTop;
uniform vec3 uSkyBottom;
uniform float uHeight;
// Contact shadows: every body as the ellipsoid inscribed in its bounding box.
#define MAX_OCCLUDERS 16
uniform int uOccluderCount;
uniform vec3 uOccCentre[MAX_OCCLUDERS];
uniform vec3 uOccRadii[MAX_OCCLUDERS];
uniform int uSelf;          // this mesh's occluder index, -1 if it is none
out vec4 fragColour;

#if SHADOWS
float shadowFactor() {
  vec4 lightPos = gl_FrontFacing ? vLightPos : vLightPosBack;
  vec3 p = lightPos.xyz / lightPos.w * 0.5 + 0.5;
  if (p.x <= 0.0 || p.x >= 1.0 || p.y <= 0.0 || p.y >= 1.0) return 1.0;
  p.z = min(p.z, 1.0);  // receivers beyond the far plane compare as "far"
  // 4 bilinear (hardware 2x2) comparisons = smooth 4x4-texel penumbra.
  float s = texture(uShadowMap, vec3(p.xy + vec2(-uShadowStep, -uShadowStep), p.z));
  s += texture(uShadowMap, vec3(p.xy + vec2(uShadowStep, -uShadowStep), p.z));
  s += texture(uShadowMap, vec3(p.xy + vec2(-uShadowStep, uShadowStep), p.z));
  s += texture(uShadowMap, vec3(p.xy + vec2(uShadowStep, uShadowStep), p.z));
  return s * 0.25;
}
#endif

// Analytic occlusion by the other bodies, each body an ellipsoid scaled to the unit sphere (the
// normal by the inverse transpose). The sphere's form factor is cos(theta) (r / d)^2 (Quilez,
// "Sphere ambient occlusion", 2013); a contact shadow should read at a glance, so this uses the
// slower cos(theta) r / d, times 1.2, faded to nothing between 1 and 2.5 radii from the centre
// (ground more than 1.25 body sizes from its centre keeps its exact colour). 1 = unoccluded.
float contactVisibility(vec3 p, vec3 n) {
  float vis = 1.0;
  for (int i = 0; i < uOccluderCount; ++i) {
    if (i == uSelf) continue;
    vec3 r = uOccRadii[i];
    vec3 q = (p - uOccCentre[i]) / r;
    float d2 = dot(q, q);
    float d = sqrt(d2);
    float cosTheta = clamp(-dot(normalize(n * r), q) / max(d, 1e-4), 0.0, 1.0);
    float fade = smoothstep(2.5, 1.0, d);
    vis *= 1.0 - min(1.2 * cosTheta / max(d, 1.0), 1.0) * fade;
  }
  return vis;
}

void main() {
#if FLAT
  // Faceted: the screen-space derivatives of the position span the triangle's plane; their
  // cross product faces the viewer.
  vec3 n = normalize(cross(dFdx(vPos), dFdy(vPos)));
#else
  vec3 n = normalize(vNormal);
  if (!gl_FrontFacing) n = -n;  // two-sided lighting
#endif
  vec3 l = uToLight;
  float ndl = max(dot(n, l), 0.0);
#if SHADOWS
  float shadow = ndl > 0.0 ? shadowFactor() : 1.0;
#else
  float shadow = 1.0;
#endif
  // Hemisphere ambient: sky light from above, light bounced off the ground from below.
  vec3 ambient = mix(uAmbientGround, uAmbientSky, 0.5 + 0.5 * n.y);
#if CONTACT
  float vis = contactVisibility(vPos, n);
#else
  float vis = 1.0;
#endif
  ambient *= vis;
  shadow *= mix(1.0, vis, 0.75);  // a contact shadow takes most direct light too
#if GROUND
  vec3 d = vPos - uGroundOrigin;
  vec2 uv = vec2(dot(d, uGroundU), dot(d, uGroundV)) / uTile;
  // Box-filtered checker: averages to grey where tiles get smaller than a pixel.
  vec2 w = fwidth(uv) + 1e-4;
  vec2 i = 2.0 * (abs(fract((uv - 0.5 * w) * 0.5) - 0.5) - abs(fract((uv + 0.5 * w) * 0.5) - 0.5)) / w;
  vec3 albedo = mix(uAlbedo, uGroundB, 0.5 - 0.5 * i.x * i.y);
  float fog = smoothstep(0.55, 1.0, length(d) / uGroundExtent);
  vec3 lit = albedo * (ambient + uLightColour * ndl * shadow);
  // The ground fades into the sky towards its edge: the sky's colour at this pixel (as the sky
  // pass draws it), mixed in here, so the sky is only drawn where nothing else is.
  float t = clamp((gl_FragCoord.y - 0.5) / max(uHeight - 1.0, 1.0), 0.0, 1.0);
  fragColour = vec4(mix(toDisplay(lit), mix(uSkyBottom, uSkyTop, t), fog), uAlpha);
#elif JELLY
  // Gelatine (translucent bodies; only their nearest surface is drawn, see translucentPass).
  vec3 v = normalize(uEye - vPos);
  float ndv = clamp(dot(n, v), 0.0, 1.0);
  vec3 h = normalize(l + v);
  // Wrap diffuse (light reaching round the terminator, as through a scattering solid).
  float wrap = max(dot(n, l) + 0.5, 0.0) / 1.5;
  // Thickness along the view ray: for a rounded body the chord through this point, ~ n.v of
  // its diameter: thin at the rim. Light from behind comes through thin parts.
  float thick = ndv;
  float transmit = exp(-3.0 * thick) * (0.5 + 0.5 * max(dot(-l, v), 0.0));
  vec3 body = uAlbedo * (ambient + uLightColour * (wrap * shadow + 0.8 * transmit));
  // Strong specular and a Fresnel rim (Schlick 1994, F0 = 0.04 for water-like gelatine)
  // reflecting the hemisphere in the mirror direction: sky above, ground below.
  float spec = ndl > 0.0 ? max(uSpecular, 0.9) * pow(max(dot(n, h), 0.0), uShininess) : 0.0;
  float fresnel = 0.04 + 0.96 * pow(1.0 - ndv, 5.0);
  vec3 env = mix(uAmbientGround, uAmbientSky, 0.5 + 0.5 * reflect(-v, n).y);
  vec3 reflected = uLightColour * spec * shadow + fresnel * env;
  // Opacity grows with the thickness: 1 - (1 - alpha)^(0.3 + n.v), alpha where n.v = 0.7.
  float opacity = 1.0 - pow(1.0 - uAlpha, 0.3 + thick);
  // Premultiplied: the body covers `opacity`, the reflection adds on top.
  fragColour = vec4(min(toDisplay(body) * opacity + toDisplay(reflected), vec3(1.0)), opacity);
#else
  vec3 v = normalize(uEye - vPos);
  vec3 h = normalize(l + v);
  float spec = ndl > 0.0 ? uSpecular * pow(max(dot(n, h), 0.0), uShininess) : 0.0;
  vec3 lit = uAlbedo * (ambient + uLightColour * ndl * shadow) + uLightColour * spec * shadow;
  fragColour = vec4(toDisplay(lit), uAlpha);
#endif
}
)";

}  // namespace

std::string meshVariantSource(bool shadows, bool ground, bool flat, bool jelly, bool contact) {
  return std::string("#version 330 core\n#define SHADOWS ") + (shadows ? "1" : "0") + "\n#define GROUND " +
         (ground ? "1" : "0") + "\n#define FLAT " + (flat ? "1" : "0") + "\n#define JELLY " + (jelly ? "1" : "0") +
         "\n#define CONTACT " + (contact ? "1" : "0") + "\n" + kLookGlsl + kMeshFsBody;
}

// FXAA-style anti-aliasing (after Lottes' FXAA, "console" variant): the luma of the 4 diagonal
// neighbours gives the edge direction; two and four taps along the edge are blended; pixels
// whose neighbourhood contrast is low keep their exact colour (texelFetch). Two passes, because
// llvmpipe runs both sides of a branch: EDGE_PASS writes every pixel's exact colour and marks
// the edge pixels in the depth buffer (depth 0, the rest 1); the blend pass, drawn at depth 0.5
// with GL_GREATER, then runs only where an edge was marked (early depth test).
namespace {
constexpr const char* kFxaaFsBody = R"(
uniform sampler2D uScene;
uniform vec2 uTexel;  // 1 / frame size
out vec4 fragColour;
float luma(vec3 c) { return dot(c, vec3(0.299, 0.587, 0.114)); }
void main() {
  ivec2 ip = ivec2(gl_FragCoord.xy);
  ivec2 hi = textureSize(uScene, 0) - 1;
  vec3 rgbM = texelFetch(uScene, ip, 0).rgb;
  float lNW = luma(texelFetch(uScene, clamp(ip + ivec2(-1, -1), ivec2(0), hi), 0).rgb);
  float lNE = luma(texelFetch(uScene, clamp(ip + ivec2(1, -1), ivec2(0), hi), 0).rgb);
  float lSW = luma(texelFetch(uScene, clamp(ip + ivec2(-1, 1), ivec2(0), hi), 0).rgb);
  float lSE = luma(texelFetch(uScene, clamp(ip + ivec2(1, 1), ivec2(0), hi), 0).rgb);
  float lM = luma(rgbM);
  float lMin = min(lM, min(min(lNW, lNE), min(lSW, lSE)));
  float lMax = max(lM, max(max(lNW, lNE), max(lSW, lSE)));
  bool edge = !(lMax - lMin < max(0.0312, lMax * 0.125));
#if EDGE_PASS
  fragColour = vec4(rgbM, 1.0);  // no edge here: the exact colour
  gl_FragDepth = edge ? 0.0 : 1.0;
#else
  if (!edge) {
    fragColour = vec4(rgbM, 1.0);
    return;
  }
  vec2 uv = gl_FragCoord.xy * uTexel;
  vec2 dir = vec2(-((lNW + lNE) - (lSW + lSE)), (lNW + lSW) - (lNE + lSE));
  float reduce = max((lNW + lNE + lSW + lSE) * (0.25 / 8.0), 1.0 / 128.0);
  float rcpDirMin = 1.0 / (min(abs(dir.x), abs(dir.y)) + reduce);
  dir = clamp(dir * rcpDirMin, vec2(-8.0), vec2(8.0)) * uTexel;
  vec3 rgbA = 0.5 * (textureLod(uScene, uv + dir * (1.0 / 3.0 - 0.5), 0.0).rgb +
                     textureLod(uScene, uv + dir * (2.0 / 3.0 - 0.5), 0.0).rgb);
  vec3 rgbB = rgbA * 0.5 + 0.25 * (textureLod(uScene, uv - dir * 0.5, 0.0).rgb +
                                   textureLod(uScene, uv + dir * 0.5, 0.0).rgb);
  float lB = luma(rgbB);
  fragColour = vec4((lB < lMin || lB > lMax) ? rgbA : rgbB, 1.0);
#endif
}
)";
}  // namespace

std::string fxaaSource(bool edgePass) {
  return std::string("#version 330 core\n#define EDGE_PASS ") + (edgePass ? "1" : "0") + "\n" + kFxaaFsBody;
}

const char* const kDepthVs = R"(#version 330 core
layout(location = 0) in vec3 aPos;
uniform mat4 uLightViewProj;
invariant gl_Position;  // also the translucent depth prepass, matched by the mesh shader
void main() { gl_Position = uLightViewProj * vec4(aPos, 1.0); }
)";
const char* const kDepthFs = R"(#version 330 core
void main() {}
)";

const char* const kSkyVs = R"(#version 330 core
void main() {
  // One triangle covering the screen.
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 1.0, 1.0);  // on the far plane: depth 1, behind everything
}
)";
// One triangle covering the screen at depth 0.5 (the FXAA blend pass).
const char* const kMidVs = R"(#version 330 core
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
)";
const char* const kSkyFs = R"(#version 330 core
uniform vec3 uTop;
uniform vec3 uBottom;
uniform float uHeight;
out vec4 fragColour;
void main() {
  float t = clamp((gl_FragCoord.y - 0.5) / max(uHeight - 1.0, 1.0), 0.0, 1.0);
  fragColour = vec4(mix(uBottom, uTop, t), 1.0);
}
)";

const char* const kOverlayVs = R"(#version 330 core
uniform vec4 uRect;  // NDC x0, y0 (top), x1, y1 (bottom)
out vec2 vUv;
void main() {
  vec2 c = vec2((gl_VertexID & 1) != 0 ? 1.0 : 0.0, (gl_VertexID & 2) != 0 ? 1.0 : 0.0);
  vUv = c;  // v = 0: first (top) texture row
  gl_Position = vec4(mix(uRect.x, uRect.z, c.x), mix(uRect.y, uRect.w, c.y), 0.0, 1.0);
}
)";
const char* const kOverlayFs = R"(#version 330 core
in vec2 vUv;
uniform sampler2D uTex;
out vec4 fragColour;
void main() { fragColour = texture(uTex, vUv); }  // premultiplied alpha
)";

}  // namespace springy::render
