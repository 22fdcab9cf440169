// frond rigid VAT, layout "houdini-vat3-rigid" (the sidecar's `layout`; export/VAT.md), as a
// Godot 3 (3.2+, GLES3 only: texelFetch) spatial material for a LOD's unskinned billboard mesh
// (`<tree>_LOD<k>_vat`). The uniforms come from the LOD's sidecar `<tree>_LOD<k>_vat.json`:
// vat_frames = `frames`, vat_fps = `fps`, vat_bound_min / vat_bound_max = `bound_min` /
// `bound_max`, vat_hdr = `hdr`, clip_start_s = `start_s`; the textures are `textures.position`,
// `textures.rotation` and `textures.pivot`; the atlas is the billboards' glTF base colour
// texture. Same decoding as frond_vat_rigid.wgsl
// (the tested reference) and frond_vat_rigid.gdshader (Godot 4).
//
// PIVOT: Godot 3's glTF importer keeps only TEXCOORD_0 and TEXCOORD_1 (as UV and UV2) and drops
// TEXCOORD_2 / TEXCOORD_3, where frond writes the rest pivot. This material therefore reads the
// pivot from the sidecar's pivot texture (`textures.pivot`, EXR half: each piece's rest pivot at
// its frame-0 texel, the column and row UV2 names). See frond_vat_pivot().
//
// Import: textures with Filter, Mipmaps and Repeat off, Compress Mode Uncompressed
// (no VRAM compression, "Detect 3D" off); use the EXR output (`--animation vat`): Godot reduces
// 16-bit PNGs to 8 bits. Mesh compression (Meshes > Compress) stores UV2 as half floats, exact
// enough for textures up to 2048 texels a side; turn it off for larger ones. Light Baking "Gen
// Lightmaps" unwraps a new UV2: leave it off.
//
// Time: the frame must follow the clip the skinned wood (and the other LODs) play. The engine's
// TIME (the default) does so only when that clip started at TIME = 0 and loops (and TIME wraps
// every rendering/limits/time/time_rollover_secs, 3600 s); otherwise turn use_engine_time off
// and set clip_time to the AnimationPlayer's current_animation_position. clip_start_s is the
// clip time of frame 0 (the sidecar's `start_s`). Godot 3 has no per-instance uniforms: instances sharing this material share
// clip_time and the LOD fade.
//
// The pieces move out of the rest mesh's bounds: give the MeshInstance an extra_cull_margin
// covering the sidecar's position_min / position_max.
//
// LOD cross-fade: lod_fade and lod_incoming, see frond_lod_dither_keep.

shader_type spatial;
render_mode cull_disabled;

uniform sampler2D vat_position;
uniform sampler2D vat_rotation;
uniform sampler2D vat_pivot;
uniform float vat_frames = 1.0;
uniform float vat_fps = 30.0;
uniform vec3 vat_bound_min = vec3(0.0, 0.0, 0.0);
uniform vec3 vat_bound_max = vec3(1.0, 1.0, 1.0);
uniform bool vat_hdr = true;
uniform float clip_start_s = 0.0;
uniform bool use_engine_time = true;
uniform float clip_time = 0.0;

uniform sampler2D albedo_atlas : hint_albedo;
uniform float alpha_scissor : hint_range(0.0, 1.0) = 0.5;
uniform float lod_fade : hint_range(0.0, 1.0) = 0.0;
uniform bool lod_incoming = false;

// The rest pivot of the piece at piece_uv (TEXCOORD_1): its frame-0 texel of the pivot texture
// (see PIVOT above).
vec3 frond_vat_pivot(vec2 piece_uv) {
	ivec2 size = textureSize(vat_pivot, 0);
	int height = textureSize(vat_position, 0).y;
	int x = clamp(int(floor(piece_uv.x * float(size.x))), 0, size.x - 1);
	int y = clamp(int(floor(piece_uv.y * float(height))), 0, size.y - 1);
	return texelFetch(vat_pivot, ivec2(x, y), 0).rgb;
}

// Rotates v by the unit quaternion q = (x, y, z, w).
vec3 frond_vat_rotate(vec4 q, vec3 v) {
	return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

// Rebuilds (x, y, z, w) from the three stored components; position alpha * 4 names the dropped,
// largest, positive component (0 = w, 1 = x, 2 = y, 3 = z) whose slot holds w.
vec4 frond_vat_decode_rotation(vec3 stored, float position_alpha) {
	float largest = sqrt(max(0.0, 1.0 - dot(stored, stored)));
	int dropped = int(floor(position_alpha * 4.0 + 0.5));
	if (dropped == 1) {
		return vec4(largest, stored.y, stored.z, stored.x);
	}
	if (dropped == 2) {
		return vec4(stored.x, largest, stored.z, stored.y);
	}
	if (dropped == 3) {
		return vec4(stored.x, stored.y, largest, stored.z);
	}
	return vec4(stored, largest);
}

// Shortest-path slerp; normalized lerp when the rotations are within ~1.8 degrees.
vec4 frond_vat_slerp(vec4 a, vec4 b_in, float t) {
	vec4 b = b_in;
	float d = dot(a, b);
	if (d < 0.0) {
		b = -b;
		d = -d;
	}
	if (d > 0.9995) {
		return normalize(mix(a, b, t));
	}
	float angle = acos(d);
	return normalize(a * sin((1.0 - t) * angle) + b * sin(t * angle));
}

// The pose of the piece at piece_uv (TEXCOORD_1) at integer frame: point-sampled texels.
void frond_vat_load(vec2 piece_uv, int frame, out vec3 position, out vec4 rotation) {
	ivec2 size = textureSize(vat_position, 0);
	int rows_per_frame = size.y / max(int(vat_frames), 1);
	int x = clamp(int(floor(piece_uv.x * float(size.x))), 0, size.x - 1);
	int y = clamp(int(floor(piece_uv.y * float(size.y))) + frame * rows_per_frame, 0, size.y - 1);
	vec4 p = texelFetch(vat_position, ivec2(x, y), 0);
	vec4 r = texelFetch(vat_rotation, ivec2(x, y), 0);
	position = p.xyz;
	vec3 stored = r.xyz;
	if (!vat_hdr) {
		position = mix(vat_bound_min, vat_bound_max, p.xyz);
		stored = r.xyz * 2.0 - 1.0;
	}
	rotation = frond_vat_decode_rotation(stored, p.w);
}

// The piece's pivot position and rotation at a fractional frame (wraps around the loop).
void frond_vat_pose(vec2 piece_uv, float frame, out vec3 position, out vec4 rotation) {
	float frames = max(vat_frames, 1.0);
	float wrapped = frame - frames * floor(frame / frames);
	float f0 = min(floor(wrapped), frames - 1.0);
	float t = wrapped - f0;
	int i0 = int(f0);
	int i1 = (i0 + 1) % int(frames);
	vec3 position_a;
	vec3 position_b;
	vec4 rotation_a;
	vec4 rotation_b;
	frond_vat_load(piece_uv, i0, position_a, rotation_a);
	frond_vat_load(piece_uv, i1, position_b, rotation_b);
	position = mix(position_a, position_b, t);
	rotation = frond_vat_slerp(rotation_a, rotation_b, t);
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
	vec3 pivot = frond_vat_pivot(UV2);
	vec3 position;
	vec4 rotation;
	frond_vat_pose(UV2, (t - clip_start_s) * vat_fps, position, rotation);
	VERTEX = frond_vat_rotate(rotation, VERTEX - pivot) + position;
	NORMAL = frond_vat_rotate(rotation, NORMAL);
	TANGENT = frond_vat_rotate(rotation, TANGENT);
	BINORMAL = frond_vat_rotate(rotation, BINORMAL);
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
