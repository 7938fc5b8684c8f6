#pragma once
// GLSL 4.50 sources of the renderer's three programs: the geometry pass (lit colour, and linear
// depth with the label in one two-channel integer target), the sky (pixels no geometry covered) and
// the weather particles blended onto the colour. Motion blur and sensor noise follow on the CPU
// (camera_effects.h).

namespace hameritt::render::shaders {

// Per-instance data are instanced vertex attributes (fetched once per instance): the culled
// records of the frame, in draw order.
inline constexpr const char* kGeometryVertex = R"GLSL(
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in uint a_material;  // Kd (sqrt-encoded RGB8) << 8 | MaterialKind
layout(location = 3) in vec4 i_row0;      // model matrix rows (mesh -> world)
layout(location = 4) in vec4 i_row1;
layout(location = 5) in vec4 i_row2;
layout(location = 6) in vec4 i_normal0;   // normal matrix rows; w: canopy scale, length, width
layout(location = 7) in vec4 i_normal1;
layout(location = 8) in vec4 i_normal2;
layout(location = 9) in uvec2 i_ids;      // colour, label

uniform mat4 u_view_proj;  // projection * world-to-optical rotation, camera-relative
uniform vec3 u_camera;     // optical centre in the world
uniform vec3 u_canopy_center;  // foliage vertices scale about it by the canopy factor
uniform vec3 u_sun_dir;
uniform vec3 u_sun_color;
uniform vec3 u_sky_ambient;
uniform vec3 u_ground_ambient;
uniform float u_snow;  // snow cover on upward surfaces
uniform float u_wet;   // rain darkens surfaces

// The meshes have one normal per face, so the lighting is constant per triangle: it is computed
// here and passed flat. Nothing is interpolated but the position. Objects (compiled without
// GROUND_LAYERS) get their final lit colour; the ground layers (lawn, streets, sidewalks) a
// colour of the form base * pattern + snow (or alt where the pattern switches colour: dry grass
// on the lawn, the centre line on a street), the pattern computed per pixel at the world point
// that the fragment shader rebuilds from the pixel and the depth.
#if defined(FACADE)
// Building facades: wall, window glass and storefront glass, lit; the pattern is laid out per
// pixel from the world point (storeys from the instance's storey height, window columns along
// the face from its per-building spacing).
flat out vec3 v_color;   // lit wall
flat out vec3 v_glass;   // lit upper-floor glass (the roof: its membrane)
flat out vec3 v_shop;    // lit storefront glass
flat out uint v_label;
flat out vec4 v_frame;   // instance origin x, y, base z, storey height (-1: roof, 0: other)
flat out vec4 v_layout;  // wall: face tangent x, y, window spacing, window width fraction;
                         // roof: length axis x, y, length, width
#elif defined(GROUND_LAYERS)
flat out vec3 v_base;   // (1 - snow cover) * light * albedo
flat out vec3 v_alt;    // (1 - snow cover) * light * the pattern's second colour
flat out vec3 v_snow;   // snow cover * light * snow
flat out uvec2 v_ids;   // label, material kind
flat out vec4 v_frame;  // instance origin x, y and unit heading x, y (street markings)
flat out vec2 v_extent; // instance length and width
#else
flat out vec3 v_color;  // lit colour
flat out uint v_label;
#endif
invariant gl_Position;

vec3 unpack8(uint c) {
  return vec3(float(c & 255u), float((c >> 8) & 255u), float((c >> 16) & 255u)) / 255.0;
}

void main() {
  uint kind = a_material & 255u;
  vec3 p = a_position;
  if (kind == 2u) p = u_canopy_center + i_normal0.w * (p - u_canopy_center);
  vec4 p4 = vec4(p, 1.0);
  vec3 world = vec3(dot(i_row0, p4), dot(i_row1, p4), dot(i_row2, p4));
  gl_Position = u_view_proj * vec4(world - u_camera, 1.0);

  vec3 n = normalize(vec3(dot(i_normal0.xyz, a_normal), dot(i_normal1.xyz, a_normal),
                          dot(i_normal2.xyz, a_normal)));
  vec3 kd = vec3(float(a_material >> 24), float((a_material >> 16) & 255u),
                 float((a_material >> 8) & 255u)) / 255.0;
  vec3 albedo = kd * kd;  // colours are stored gamma-2 encoded
  vec3 alt = kind == 4u ? vec3(0.62, 0.45, 0.06) : vec3(0.26, 0.25, 0.13);  // dash, dry grass
  if (kind == 1u || kind == 6u) {
    albedo = unpack8(i_ids.x);
    albedo *= albedo;
  } else if (kind == 2u) {
    albedo *= 2.0 * unpack8(i_ids.x);
  }
  float keep = 1.0;
  if (u_wet > 0.0) keep = 1.0 - u_wet * (0.18 + 0.22 * max(n.z, 0.0));
  // Snow lies on upward surfaces; traffic clears part of it from the streets.
  float cover = u_snow * (kind == 4u ? 0.55 : 1.0) * smoothstep(0.3, 0.85, n.z);
  vec3 light = u_sun_color * max(dot(n, u_sun_dir), 0.0) +
               mix(u_ground_ambient, u_sky_ambient, 0.5 + 0.5 * n.z);
  vec3 snow = cover * light * vec3(0.82, 0.84, 0.88);
#if defined(FACADE)
  v_color = (1.0 - cover) * keep * light * albedo + snow;
  v_label = i_ids.y;
  // Glass: a dark body that mirrors part of the sky; shop windows show a lit interior.
  v_glass = keep * (light * vec3(0.030, 0.038, 0.050) + 0.28 * u_sky_ambient);
  v_shop = keep * (light * vec3(0.10, 0.085, 0.06) + 0.18 * u_sky_ambient + vec3(0.05, 0.04, 0.025));
  // Per-building layout from the instance label (the world's seed decides the ids).
  uint h = (i_ids.y & 65535u) * 2654435761u;
  float r0 = float((h >> 8) & 255u) / 255.0, r1 = float((h >> 16) & 255u) / 255.0;
  bool wall = abs(n.z) < 0.3, roof = n.z > 0.7;
  v_frame = vec4(i_row0.w, i_row1.w, i_row2.w, wall ? i_normal0.w : (roof ? -1.0 : 0.0));
  v_layout = vec4(-n.y, n.x, 1.4 + 1.4 * r0, 0.5 + 0.3 * r1);
  if (kind == 7u) {
    // A traffic-light mast: the lamps of the axis its face looks along (i_ids.x: signalLamps).
    float h0 = float((i_ids.x >> 8) & 255u) * (6.2831853 / 256.0);
    bool along0 = abs(dot(n.xy, vec2(cos(h0), sin(h0)))) > 0.7;
    uint lit = along0 ? (i_ids.x & 3u) : ((i_ids.x >> 2) & 3u);
    uint arrow = along0 ? ((i_ids.x >> 4) & 1u) : ((i_ids.x >> 5) & 1u);
    // The cross street's protected left arrow lets this street's right turns go.
    uint right = along0 ? ((i_ids.x >> 5) & 1u) : ((i_ids.x >> 4) & 1u);
    v_frame = vec4(i_row0.w, i_row1.w, i_row2.w, wall ? -2.0 : 0.0);
    // x: the lit lamp, plus 4 with the left arrow, plus 8 with the right arrow; zw: the face's
    // horizontal, to the viewer's right.
    v_layout = vec4(float(lit + 4u * arrow + 8u * right), i_row2.z, -n.y, n.x);
  } else if (roof) {
    // The roof: membrane and a parapet cap in the wall colour.
    v_layout = vec4(vec2(i_row0.x, i_row1.x) / max(i_normal1.w, 1e-6), i_normal1.w, i_normal2.w);
    v_glass = (1.0 - cover) * keep * light * vec3(0.16, 0.16, 0.17) + snow;
  }
#elif defined(GROUND_LAYERS)
  v_base = (1.0 - cover) * keep * light * albedo;
  v_alt = (1.0 - cover) * keep * light * alt;
  v_snow = snow;
  v_extent = vec2(i_normal1.w, i_normal2.w);
  v_frame = vec4(i_row0.w, i_row1.w, vec2(i_row0.x, i_row1.x) / max(v_extent.x, 1e-6));
  v_ids = uvec2(i_ids.y, kind);
#else
  v_color = (1.0 - cover) * keep * light * albedo + snow;
  v_label = i_ids.y;
#endif
}
)GLSL";

inline constexpr const char* kCommon = R"GLSL(
uniform vec3 u_haze_color;
uniform float u_haze_k;

// A soft shoulder (Reinhard-like), then a display gamma of 2 (colours are defined in a gamma-2
// space and squared to linear: cheaper than pow() on a CPU rasterizer).
vec3 toDisplay(vec3 c) {
  return sqrt(c / (vec3(1.0) + 0.25 * c));
}
// Fog, dust and rain: exponential extinction towards the haze colour.
vec3 haze(vec3 c, float distance) {
  if (u_haze_k > 0.0) c = mix(u_haze_color, c, exp(-u_haze_k * distance));
  return c;
}
)GLSL";

inline constexpr const char* kGeometryFragment = R"GLSL(
#if defined(FACADE)
flat in vec3 v_color;
flat in vec3 v_glass;
flat in vec3 v_shop;
flat in uint v_label;
flat in vec4 v_frame;
flat in vec4 v_layout;
#elif defined(GROUND_LAYERS)
flat in vec3 v_base;
flat in vec3 v_alt;
flat in vec3 v_snow;
flat in uvec2 v_ids;
flat in vec4 v_frame;
flat in vec2 v_extent;
#else
flat in vec3 v_color;
flat in uint v_label;
#endif

layout(location = 0) out vec4 o_color;
layout(location = 1) out uvec2 o_depth_label;  // depth (float bits), semantic << 16 | instance

uniform float u_near;
uniform float u_far;
uniform vec3 u_camera;
uniform mat3 u_world_R_optical;
uniform vec4 u_intrinsics;  // fx, fy, cx, cy
// Clear air (aerial perspective) and weather haze together: one extinction coefficient and the
// in-scattered colour of both media, c = mix(u_extinction_color, c, exp(-k d)).
uniform vec3 u_extinction_color;
uniform float u_extinction_k;

#ifdef GROUND_LAYERS
float hash21(vec2 p) {
  uvec2 q = uvec2(ivec2(floor(p)) + 32768) * uvec2(1597334673u, 3812015801u);
  uint n = (q.x ^ q.y) * 1597334673u;
  return float(n >> 8) * (1.0 / 16777216.0);
}
float valueNoise(vec2 p) {
  vec2 i = floor(p), f = fract(p);
  vec2 u = f * f * (3.0 - 2.0 * f);
  return mix(mix(hash21(i), hash21(i + vec2(1, 0)), u.x),
             mix(hash21(i + vec2(0, 1)), hash21(i + vec2(1, 1)), u.x), u.y);
}
#endif

void main() {
  // Distance along the optical axis from the reversed-Z window depth (exact inverse of the
  // projection): z_w = n (f - Z) / (Z (f - n)).
  float depth = u_near * u_far / (gl_FragCoord.z * (u_far - u_near) + u_near);
  // The pixel's ray (optical z = 1; rows top first: window y = v + 0.5).
  vec3 ray = vec3((gl_FragCoord.x - 0.5 - u_intrinsics.z) / u_intrinsics.x,
                  (gl_FragCoord.y - 0.5 - u_intrinsics.w) / u_intrinsics.y, 1.0);
#ifdef GROUND_LAYERS
  uint kind = v_ids.y;
  vec3 c = v_base;
  if (kind >= 3u) {
    // Ground layers: patterns in world coordinates.
    vec2 w = depth * (u_world_R_optical * ray).xy + u_camera.xy;
    if (kind == 3u) {
      float patches = valueNoise(w * (1.0 / 9.0));
      c = mix(v_base * (0.8 + 0.4 * patches), v_alt, 0.4 * smoothstep(0.6, 0.95, patches));
    } else if (kind == 4u) {
      // Asphalt, and a dashed yellow centre line, not across the crossings at either end.
      vec2 d = w - v_frame.xy;
      float along = dot(d, v_frame.zw), across = dot(d, vec2(-v_frame.w, v_frame.z));
      float open = 0.5 * v_extent.x - v_extent.y - 1.0;
      if (abs(across) < 0.07 && abs(along) < open && fract(along / 6.0) < 0.5) {
        c = v_alt;
      } else {
        c = v_base * (0.85 + 0.3 * valueNoise(w * 0.9));
      }
    } else {
      c = v_base * (0.92 + 0.12 * valueNoise(w * 1.7));
    }
  }
  c += v_snow;
  uint label = v_ids.x;
#elif defined(FACADE)
  vec3 c = v_color;
  uint label = v_label;
  vec3 w = depth * (u_world_R_optical * ray) + u_camera;
  if (v_frame.w > 0.0) {
    // Window bands on every storey above the ground floor; storefronts (tall glass between
    // piers every 3 m, a sign band above) on the ground floor.
    float z = (w.z - v_frame.z) / v_frame.w;
    float fz = fract(z);
    float u = dot(w.xy - v_frame.xy, v_layout.xy);
    if (z < 1.0) {
      if (fz > 0.06 && fz < 0.72 && fract(u / 3.0 + 0.5) > 0.08) c = v_shop;
      else if (fz > 0.78) c = 0.55 * v_color;
    } else if (fz > 0.3 && fz < 0.82 && abs(fract(u / v_layout.z) - 0.5) < 0.5 * v_layout.w) {
      c = v_glass;
    }
  } else if (v_frame.w < -1.5) {
    // Signal lamps in the top 1.2 m of a mast's face: red, yellow, green from the top.
    float below = v_frame.z + v_layout.y - w.z;
    if (below < 1.2) {
      float band = min(floor(below / 0.4), 2.0);
      vec3 lamp = band < 0.5 ? vec3(1.6, 0.1, 0.05)
                             : (band < 1.5 ? vec3(1.6, 0.9, 0.05) : vec3(0.1, 1.5, 0.4));
      float lit = mod(v_layout.x, 4.0);
      bool on = abs(band - lit) < 0.5;
      if (v_layout.x > 3.5 && band > 1.5) {
        // A protected arrow in the green lamp's place: a shaft and a head pointing left (this
        // street's left arrow) or right (the cross street's arrow, when right turns go).
        vec2 p = vec2(dot(w.xy - v_frame.xy, v_layout.zw), below - 1.0) / 0.2;
        if (v_layout.x > 7.5) p.x = -p.x;
        on = (p.x > -0.2 && p.x < 0.8 && abs(p.y) < 0.18) ||
             (p.x > -0.8 && p.x <= -0.2 && abs(p.y) < p.x + 0.8);
      }
      c = on ? lamp : 0.04 * lamp;
    }
  } else if (v_frame.w < 0.0) {
    vec2 d = w.xy - v_frame.xy;
    vec2 q = vec2(dot(d, v_layout.xy), dot(d, vec2(-v_layout.y, v_layout.x)));
    vec2 room = 0.5 * v_layout.zw;
    vec2 e = room - abs(q);
    // The membrane and a parapet cap in the wall colour; the rooftop equipment is solid
    // geometry of its own (scene.cpp, rooftopEquipment).
    c = min(e.x, e.y) < 0.35 ? v_color : v_glass;
  }
#else
  vec3 c = v_color;
  uint label = v_label;
#endif
  c = mix(u_extinction_color, c, exp(-u_extinction_k * depth * length(ray)));
  o_color = vec4(toDisplay(c), 1.0);
  o_depth_label = uvec2(floatBitsToUint(depth), label);
}
)GLSL";

// A full-screen triangle at the far plane (window depth 0), drawn with GL_EQUAL after the
// geometry, so it shades only the pixels nothing covered (and every one of them: the colour
// and depth-label targets need no clearing).
inline constexpr const char* kFullscreenVertex = R"GLSL(
#version 450 core
void main() {
  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
)GLSL";

inline constexpr const char* kSkyFragment = R"GLSL(
layout(location = 0) out vec4 o_color;
layout(location = 1) out uvec2 o_depth_label;

uniform mat3 u_world_R_optical;
uniform vec4 u_intrinsics;  // fx, fy, cx, cy
uniform vec3 u_zenith;
uniform vec3 u_horizon;
uniform vec3 u_sun_dir;
uniform vec3 u_glow;
uniform float u_far;

void main() {
  // Rows are rendered top first: window (x, y) is pixel (u, v) = (x - 0.5, y - 0.5).
  vec2 uv = gl_FragCoord.xy - 0.5;
  vec3 ray = vec3((uv.x - u_intrinsics.z) / u_intrinsics.x, (uv.y - u_intrinsics.w) / u_intrinsics.y, 1.0);
  vec3 d = normalize(u_world_R_optical * ray);
  float up = max(d.z, 0.0);
  vec3 c = mix(u_horizon, u_zenith, pow(up, 0.6));
  if (d.z < 0.0) c = u_horizon * (1.0 - 0.3 * min(-d.z * 4.0, 1.0));
  float s = max(dot(d, u_sun_dir), 0.0);
  c += u_glow * (0.35 * pow(s, 8.0) + 2.0 * pow(s, 600.0));
  c = haze(c, u_far);
  o_color = vec4(toDisplay(c), 1.0);
  o_depth_label = uvec2(0x7F800000u, 0u);  // depth +inf: nothing hit; label 0
}
)GLSL";

// PCG-based 4D hash (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020): a
// counter-based generator, so every value depends only on its inputs, never on threads or order.
inline constexpr const char* kHash = R"GLSL(
uvec4 pcg4d(uvec4 v) {
  v = v * 1664525u + 1013904223u;
  v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
  v ^= v >> 16u;
  v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
  return v;
}
vec4 uniform01(uvec4 h) { return vec4(h >> 8u) * (1.0 / 16777216.0); }
)GLSL";

// Weather particles: one screen-space particle per cell of a grid (a rain streak or a snow
// flake), present with probability `density`, drawn as an instanced quad (a four-vertex strip)
// and blended onto the colour. Each instance is a cell; its particle comes from the hash of (cell,
// layer, key).
inline constexpr const char* kParticleVertex = R"GLSL(
uniform uvec4 u_key;
uniform vec2 u_size;       // image width, height
uniform int u_cells_x;
uniform float u_cell;      // cell size (px)
uniform float u_length;    // streak length (px); 0: a flake
uniform float u_radius;    // half width of a streak, radius of a flake (px)
uniform float u_density;
uniform uint u_layer;
uniform vec3 u_fall;       // falling direction in the optical frame
uniform vec4 u_intrinsics; // fx, fy, cx, cy

out vec2 v_coord;  // streak: (along, across) in px from the centre; flake: offset in px
flat out float v_half_length;

void main() {
  int cell = gl_InstanceID;
  vec2 id = vec2(float(cell % u_cells_x), float(cell / u_cells_x));
  vec4 h = uniform01(pcg4d(uvec4(uint(cell), u_layer, u_key.x, u_key.y)));
  // A triangle strip of four corners.
  vec2 corner = vec2(float(gl_VertexID & 1) * 2.0 - 1.0, float(gl_VertexID >> 1) * 2.0 - 1.0);
  vec2 p;
  if (h.x >= u_density) {
    gl_Position = vec4(2.0, 2.0, 0.5, 1.0);  // no particle in this cell: outside the view
    v_coord = vec2(0.0);
    v_half_length = 0.0;
    return;
  }
  if (u_length > 0.0) {
    // Image-plane motion of a falling drop at the cell centre: towards the vanishing point of
    // the fall direction, as fast as a level view sees it at most.
    vec2 c0 = (id + 0.5) * u_cell;
    vec2 f = vec2(u_intrinsics.x * u_fall.x - (c0.x - u_intrinsics.z) * u_fall.z,
                  u_intrinsics.y * u_fall.y - (c0.y - u_intrinsics.w) * u_fall.z) / u_intrinsics.x;
    float speed = clamp(length(f), 0.15, 1.0);
    vec2 dir = normalize(f + vec2(1e-4, 0.0));
    float half_len = 0.5 * u_length * speed * (0.7 + 0.3 * h.w);
    vec2 center = c0 + (h.yz - 0.5) * (u_cell - u_length - 2.0);
    vec2 across = vec2(-dir.y, dir.x);
    float ext_along = half_len + u_radius + 1.0, ext_across = u_radius + 1.0;
    p = center + corner.x * ext_along * dir + corner.y * ext_across * across;
    v_coord = vec2(corner.x * ext_along, corner.y * ext_across);
    v_half_length = half_len;
  } else {
    float r = u_radius * (0.6 + 0.4 * h.w);
    vec2 center = (id + 0.5) * u_cell + (h.yz - 0.5) * (u_cell - 2.0 * r - 2.0);
    p = center + corner * (r + 1.0);
    v_coord = corner * (r + 1.0);
    v_half_length = r;
  }
  // Pixel (u, v) centre -> NDC, rows top first as in the geometry pass.
  gl_Position = vec4(2.0 * (p + 0.5) / u_size - 1.0, 0.5, 1.0);
}
)GLSL";

inline constexpr const char* kParticleFragment = R"GLSL(
in vec2 v_coord;
flat in float v_half_length;
layout(location = 0) out vec4 o_color;
uniform float u_length;
uniform float u_radius;
uniform float u_alpha;
uniform float u_brightness;

void main() {
  float a;
  if (u_length > 0.0) {
    vec2 d = vec2(max(abs(v_coord.x) - v_half_length, 0.0), v_coord.y);
    a = u_alpha * clamp(1.0 - length(d) / u_radius, 0.0, 1.0);
  } else {
    a = u_alpha * (1.0 - smoothstep(0.5 * v_half_length, v_half_length, length(v_coord)));
  }
  o_color = vec4(vec3(u_brightness), a);
}
)GLSL";

}  // namespace hameritt::render::shaders
