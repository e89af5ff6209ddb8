#version 450
// Ray-casts one annotation primitive (sphere, or two spheres joined by their
// tangent cone) for this pixel: premultiplied shaded colour, view depth, and
// the window depth the depth test keeps the nearest primitive by.
#extension GL_GOOGLE_include_directive : require
#include "shared/imposter_params.h"

layout(std430, binding = 0) readonly buffer Primitives { ImposterPrimitive prims[]; };
layout(std140, binding = 1) uniform View { ImposterView V; };

layout(location = 0) flat in uint prim_index;
layout(location = 0) out vec4 out_color;  // premultiplied
layout(location = 1) out float out_depth; // view depth, world units

// Nearest hit t >= 0 of the ray o + t rd (rd unit) with sphere (c, r); -1: none.
float hit_sphere(vec3 ro, vec3 rd, vec3 c, float r, out vec3 n) {
  vec3 oc = ro - c;
  float b = dot(oc, rd);
  float h = b * b - (dot(oc, oc) - r * r);
  if (h < 0.0) return -1.0;
  float t = -b - sqrt(h);
  if (t < 0.0) return -1.0;  // the eye is inside: no front surface
  n = normalize(oc + t * rd);
  return t;
}

// Nearest hit with the convex hull of spheres (pa, ra) and (pb, rb): the cone
// tangent to both, or one of the two spherical caps. The body is a quadric in
// t restricted to the part between the tangent circles.
float hit_round_cone(vec3 ro, vec3 rd, vec3 pa, vec3 pb, float ra, float rb, out vec3 n) {
  vec3 ba = pb - pa, oa = ro - pa, ob = ro - pb;
  float rr = ra - rb;
  float m0 = dot(ba, ba), m1 = dot(ba, oa), m2 = dot(ba, rd), m3 = dot(rd, oa), m5 = dot(oa, oa);
  float m6 = dot(ob, rd), m7 = dot(ob, ob);
  float d2 = m0 - rr * rr;  // squared length of the tangent segment; <= 0: one sphere holds the other
  if (d2 > 0.0) {
    float k2 = d2 - m2 * m2;
    float k1 = d2 * m3 - m1 * m2 + m2 * rr * ra;
    float k0 = d2 * m5 - m1 * m1 + m1 * rr * ra * 2.0 - m0 * ra * ra;
    float h = k1 * k1 - k0 * k2;
    if (h >= 0.0 && k2 != 0.0) {
      float t = (-sqrt(h) - k1) / k2;
      float y = m1 - ra * rr + t * m2;
      if (t >= 0.0 && y > 0.0 && y < d2) {
        n = normalize(d2 * (oa + t * rd) - ba * y);
        return t;
      }
    }
  }
  vec3 na, nb;
  float ta = hit_sphere(ro, rd, pa, ra, na), tb = hit_sphere(ro, rd, pb, rb, nb);
  if (ta >= 0.0 && (tb < 0.0 || ta <= tb)) { n = na; return ta; }
  if (tb >= 0.0) { n = nb; return tb; }
  return -1.0;
}

void main() {
  ImposterPrimitive p = prims[prim_index];
  vec2 ndc = (2.0 * gl_FragCoord.xy - V.size.xy) / V.size.xy;
  vec3 d = V.forward.xyz + ndc.x * V.right.xyz - ndc.y * V.up.xyz;
  float len = length(d);
  vec3 rd = d / len;
  vec3 n;
  float t = p.b.w < 0.0 ? hit_sphere(vec3(0.0), rd, p.a.xyz, p.a.w, n)
                        : hit_round_cone(vec3(0.0), rd, p.a.xyz, p.b.xyz, p.a.w, p.b.w, n);
  if (t < 0.0) discard;
  float view_depth = t / len;  // d . forward_unit = 1: t along d is depth along the view axis
  // A headlight: ambient plus Lambert towards the eye, so shape reads without a scene light.
  float lambert = max(dot(n, -rd), 0.0);
  vec3 rgb = p.color.rgb * (0.3 + 0.7 * lambert);
  out_color = vec4(rgb * p.color.a, p.color.a);
  out_depth = view_depth;
  gl_FragDepth = view_depth / (view_depth + V.size.z);
}
