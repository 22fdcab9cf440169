// frond spectral billboard motion, layout "frond-spectral-2" (the sidecar's `layout`;
// export/src/spectral.rs), as a Godot 3 (3.2+, GLES3 only: texelFetch) spatial material for a
// LOD's skinned billboards. The uniforms come from the LOD's sidecar
// `<tree>_LOD<k>_spectral.json`: spectral_terms = `terms`, spectral_per_row = `per_row`,
// spectral_start_s = `start_s`, spectral_period_s = `period_s`; the texture is `texture` (RGBA
// half EXR); the atlas is the billboards' glTF base colour texture. Same sum as
// frond_spectral.wgsl (the tested reference) and frond_spectral.gdshader (Godot 4).
//
// Godot's glTF importer keeps glTF's axes and UV origin: TEXCOORD_1.x = billboard index + 0.5
// arrives as UV2.x, texture rows stay top row first. Import the EXR with Filter, Mipmaps and
// Repeat off, Compress Mode Uncompressed ("Detect 3D" off). Mesh compression
// (Meshes > Compress) stores UV2 as half floats, exact for the index only below 1024
// billboards; turn it off for more. Light Baking "Gen Lightmaps" unwraps a new UV2: leave it
// off.
//
// Time: the loop fraction must follow the clip the skeleton plays. Set clip_time to the
// AnimationPlayer's current_animation_position (use_engine_time off), or leave use_engine_time
// on when the clip was started at TIME = 0 and loops (TIME wraps every
// rendering/limits/time/time_rollover_secs, 3600 s). Godot 3 has no per-instance uniforms:
// instances sharing this material share clip_time and the LOD fade.
//
// Space: frond adds the offset before skinning, in the followed bone's rest frame. Godot skins
// before vertex() runs, so here the offset lands in the mesh's space after skinning: off by
// the bone's rotation from its rest pose (a few percent of a small offset for bones turned by a
// few degrees; exact for bones at rest).
//
// LOD cross-fade: lod_fade and lod_incoming, see frond_lod_dither_keep.

shader_type spatial;
render_mode cull_disabled;

uniform sampler2D spectral_coefficients;
uniform int spectral_terms = 1;
uniform int spectral_per_row = 1;
uniform float spectral_start_s = 0.0;
uniform float spectral_period_s = 1.0;
uniform bool use_engine_time = true;
uniform float clip_time = 0.0;

uniform sampler2D albedo_atlas : hint_albedo;
uniform float alpha_scissor : hint_range(0.0, 1.0) = 0.5;
uniform float lod_fade : hint_range(0.0, 1.0) = 0.0;
uniform bool lod_incoming = false;

// Sum of a_j cos(2 pi f_j u + phi_j) per axis over billboard i's terms: its block of 2 terms
// texels starts at column 2 terms (i % per_row) of row i / per_row (texel 2j: f, a_xyz;
// texel 2j+1: phi_xyz). Unused terms are zero and add nothing.
vec3 frond_spectral_offset(int i, float u) {
	int per_row = max(spectral_per_row, 1);
	int row = i / per_row;
	int base = 2 * spectral_terms * (i % per_row);
	vec3 offset = vec3(0.0, 0.0, 0.0);
	for (int j = 0; j < spectral_terms; j++) {
		vec4 fa = texelFetch(spectral_coefficients, ivec2(base + 2 * j, row), 0);
		vec4 ph = texelFetch(spectral_coefficients, ivec2(base + 2 * j + 1, row), 0);
		offset += fa.yzw * cos(vec3(6.28318530718 * fa.x * u) + ph.xyz);
	}
	return offset;
}

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

void vertex() {
	float t = clip_time;
	if (use_engine_time) {
		t = TIME;
	}
	int i = int(floor(UV2.x));
	float u = fract((t - spectral_start_s) / spectral_period_s);
	VERTEX += frond_spectral_offset(i, u);
}

void fragment() {
	vec4 albedo = texture(albedo_atlas, UV);
	if (albedo.a < alpha_scissor) {
		discard;
	}
	if (!frond_lod_dither_keep(lod_fade, FRAGCOORD.xy, lod_incoming)) {
		discard;
	}
	ALBEDO = albedo.rgb;
	METALLIC = 0.0;
	ROUGHNESS = 1.0;
}
