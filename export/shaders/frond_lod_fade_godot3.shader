// frond LOD cross-fade (dithered), no texture layout: a Godot 3 (3.2+) spatial material for the
// LODs that carry no frond motion texture (the input LOD0 and skinned billboard LODs, whose
// motion is the glTF skin), with the glTF material's base colour texture and alpha cutoff. The
// VAT and spectral materials hold the same two functions. Equivalent to frond_lod_dither.wgsl
// (its contract, tested) and frond_lod_fade.gdshader (Godot 4).
//
// LOD k fades into LOD k+1 over a band the engine picks (distance or screen size): set lod_fade
// from 0 (LOD k only) to 1 (LOD k+1 only) on both materials, with lod_incoming false on LOD k's
// and true on LOD k+1's. Godot 3 has no per-instance uniforms: each fading instance needs its
// own material (or MultiMesh INSTANCE_CUSTOM in place of the uniforms).

shader_type spatial;
render_mode cull_disabled;

uniform sampler2D albedo_texture : hint_albedo;
uniform vec4 albedo_color : hint_color = vec4(1.0, 1.0, 1.0, 1.0);
uniform float alpha_scissor : hint_range(0.0, 1.0) = 0.5;
uniform float metallic : hint_range(0.0, 1.0) = 0.0;
uniform float roughness : hint_range(0.0, 1.0) = 1.0;
uniform float lod_fade : hint_range(0.0, 1.0) = 0.0;
uniform bool lod_incoming = false;

// Ordered-dither threshold (b + 0.5) / 16 of the pixel at frag_xy, b its 4x4 Bayer index
// (rows 0 8 2 10 / 12 4 14 6 / 3 11 1 9 / 15 7 13 5) from the bits of x and y.
float frond_lod_dither_threshold(vec2 frag_xy) {
	vec2 p = floor(frag_xy) - 4.0 * floor(floor(frag_xy) / 4.0);
	vec2 lo = p - 2.0 * floor(p / 2.0);
	vec2 hi = floor(p / 2.0);
	float b = 8.0 * abs(lo.x - lo.y) + 4.0 * lo.y + 2.0 * abs(hi.x - hi.y) + hi.y;
	return (b + 0.5) / 16.0;
}

// LOD k fading into LOD k+1: fade 0 shows LOD k only, 1 LOD k+1 only; draw LOD k with incoming
// false and LOD k+1 with incoming true, and each keeps the pixels the other discards, so every
// pixel is drawn exactly once. Relies on every LOD playing the sampled clip in phase (the same
// clip time for the skinned LODs and this material) and on both using the same fade.
bool frond_lod_dither_keep(float fade, vec2 frag_xy, bool incoming) {
	bool to_incoming = frond_lod_dither_threshold(frag_xy) < fade;
	return to_incoming == incoming;
}

void fragment() {
	vec4 albedo = texture(albedo_texture, UV) * albedo_color;
	if (albedo.a < alpha_scissor) {
		discard;
	}
	if (!frond_lod_dither_keep(lod_fade, FRAGCOORD.xy, lod_incoming)) {
		discard;
	}
	ALBEDO = albedo.rgb;
	METALLIC = metallic;
	ROUGHNESS = roughness;
}
