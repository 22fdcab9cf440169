extends SceneTree
# Loads models the editor imported (addons/frond_import) as a game would, prints one JSON line per
# model with what Godot made of it (skeletons, animation players and clips, every mesh's surfaces
# and materials, the errors Godot printed importing and loading it) and renders it to PNG at each
# requested clip time, twice: as imported, and with the textures sampled as frond render samples
# them (_set_frond_sampling).
#
# Run by run.sh:  godot3 --path PROJECT --resolution WxH -s res://inspect.gd
# res://frond_inspect.txt, one model a line, tab-separated:
#   name  res://path.glb  /abs/out/stem  times  clip  bounds  vat
# `times` is a space-separated list of clip times (s); each writes <stem>.t<time>.godot.png and
# <stem>.t<time>.godot_frondsampling.png, the time as written in the list. `clip` may be empty
# (the first animation); `bounds` is "minx,miny,minz,maxx,maxy,maxz" (frond inspect's rest-pose
# bounds, so that the camera is frond render's) or empty (the meshes' AABB). `vat` is the path of
# a VAT LOD's sidecar (or empty): its `_vat` mesh then gets the shipped Godot 3 VAT material
# (res://frond_vat_rigid_godot3.shader, the sidecar's numbers, the textures imported beside the
# model, the mesh's own atlas) and each frame plays it at that clip time (_set_vat).
# res://frond_import_result.txt (the plugin's) supplies each model's import log.
#
# The camera is `frond render`'s (render/src/camera.rs, Camera::framing): perspective, vertical
# field of view 40 degrees, looking at the centre of the bounds from `azimuth`/`elevation`
# (FROND_GODOT_AZIMUTH, FROND_GODOT_ELEVATION; defaults 0 and 10: from +Z, slightly above) at the
# distance where the bounds' sphere fills the view. The background is BACKGROUND (magenta) so the
# silhouette is every pixel that is not; one directional light, ambient light, no tonemapping.
# The clip is posed at each time and paused there.

const Log := preload("res://frond_log.gd")
const JOBS := "res://frond_inspect.txt"
const IMPORTS := "res://frond_import_result.txt"
const BACKGROUND := Color(1, 0, 1)
const FOV_Y := 40.0

var stage: Spatial
var camera: Camera


func _init() -> void:
	call_deferred("_run")


func _run() -> void:
	var jobs := _read_jobs()
	var imports := _read_imports()
	_make_stage()
	# Let the first frames (shader compilation for the stage) pass before the first model.
	for _i in range(2):
		yield(VisualServer, "frame_post_draw")
	for job in jobs:
		var offset := Log.size()
		var record := {"file": job["name"], "res": job["res"]}
		var imported: Dictionary = imports.get(job["res"], {})
		record["imported"] = imported.get("imported", false)
		record["import_ms"] = imported.get("import_ms", -1)
		record["import_log"] = imported.get("log", [])
		var packed = null
		if ResourceLoader.exists(job["res"]):
			packed = load(job["res"])
		record["loaded"] = packed is PackedScene
		if record["loaded"]:
			var scene: Node = packed.instance()
			stage.add_child(scene)
			_describe(scene, record)
			var vat_material: ShaderMaterial = null
			if job["vat"] != "":
				vat_material = _set_vat(scene, job, record)
			record["camera"] = _frame(job["bounds"], record)
			record["renders"] = []
			for time in job["times"]:
				var render := _pose(scene, job["clip"], float(time))
				if vat_material != null:
					vat_material.set_shader_param("clip_time", float(time))
				var base: String = job["out"] + ".t" + time
				# As imported.
				_set_frond_sampling(scene, false)
				for _i in range(3):
					yield(VisualServer, "frame_post_draw")
				render["png"] = base + ".godot.png"
				render["saved"] = _save_frame(render["png"])
				# Sampled as frond render samples: Godot's box-filtered mips thin alpha-tested
				# foliage at a distance, and repeat wraps foliage cards whose UVs leave [0, 1];
				# sampled alike, the two renderers should agree on coverage, not only on shape.
				render["textures_changed"] = _set_frond_sampling(scene, true)
				for _i in range(2):
					yield(VisualServer, "frame_post_draw")
				render["png_frond_sampling"] = base + ".godot_frondsampling.png"
				_save_frame(render["png_frond_sampling"])
				record["renders"].append(render)
			_set_frond_sampling(scene, false)
			stage.remove_child(scene)
			scene.free()
		record["log"] = Log.entries(offset)
		print(to_json(record))
	quit()


# Puts the shipped Godot 3 VAT material on the scene's `_vat` mesh, its uniforms from the sidecar
# (job["vat"]) and its textures imported beside the model; the clip time is set per frame.
# Records {"mesh", "textures", "frames", "fps"} under record["vat"]; null when nothing was set.
func _set_vat(scene: Node, job: Dictionary, record: Dictionary) -> ShaderMaterial:
	var f := File.new()
	if f.open(job["vat"], File.READ) != OK:
		record["vat"] = {"error": "cannot read " + job["vat"]}
		return null
	var parsed := JSON.parse(f.get_as_text())
	f.close()
	if parsed.error != OK or not (parsed.result is Dictionary):
		record["vat"] = {"error": "the sidecar is not JSON"}
		return null
	var sidecar: Dictionary = parsed.result
	var target: MeshInstance = null
	for node in _all(scene, []):
		if node is MeshInstance and node.name.ends_with("_vat"):
			target = node
	if target == null or target.mesh == null:
		record["vat"] = {"error": "no _vat mesh"}
		return null
	var dir: String = job["res"].get_base_dir()
	var textures: Dictionary = sidecar["textures"]
	var material := ShaderMaterial.new()
	material.shader = load("res://frond_vat_rigid_godot3.shader")
	var loaded := true
	for key in ["position", "rotation", "pivot"]:
		var texture = load(dir + "/" + textures[key]) if textures.has(key) else null
		loaded = loaded and texture is Texture
		material.set_shader_param("vat_" + key, texture)
	material.set_shader_param("vat_frames", float(sidecar["frames"]))
	material.set_shader_param("vat_fps", float(sidecar["fps"]))
	var lo: Array = sidecar["bound_min"]
	var hi: Array = sidecar["bound_max"]
	material.set_shader_param("vat_bound_min", Vector3(lo[0], lo[1], lo[2]))
	material.set_shader_param("vat_bound_max", Vector3(hi[0], hi[1], hi[2]))
	material.set_shader_param("vat_hdr", bool(sidecar["hdr"]))
	material.set_shader_param("clip_start_s", float(sidecar.get("start_s", 0.0)))
	material.set_shader_param("use_engine_time", false)
	var atlas = target.mesh.surface_get_material(0)
	if atlas is SpatialMaterial:
		material.set_shader_param("albedo_atlas", atlas.albedo_texture)
		material.set_shader_param("alpha_scissor", atlas.params_alpha_scissor_threshold)
	target.material_override = material
	# The pieces leave the rest mesh's bounds.
	target.extra_cull_margin = 16384.0
	record["vat"] = {
		"mesh": target.name, "textures": loaded, "atlas": atlas is SpatialMaterial,
		"frames": sidecar["frames"], "fps": sidecar["fps"],
	}
	return material


func _save_frame(path: String) -> bool:
	var image := root.get_texture().get_data()
	image.flip_y()
	image.convert(Image.FORMAT_RGBA8)
	return image.save_png(path) == OK


# Texture flags as imported, to restore after frond-like sampling.
var imported_flags := {}


# frond_like: samples the albedo textures as frond render does: mipmaps off everywhere, and
# repeat off on alpha-scissored (foliage) materials, whose glTF samplers frond writes as
# CLAMP_TO_EDGE (Godot 3.2's glTF importer ignores samplers: every texture repeats). Otherwise
# restores the flags as imported. Returns how many textures it changed.
func _set_frond_sampling(scene: Node, frond_like: bool) -> int:
	var changed := 0
	for node in _all(scene, []):
		if not (node is MeshInstance) or node.mesh == null:
			continue
		for s in range(node.mesh.get_surface_count()):
			var material = node.get_surface_material(s)
			if material == null:
				material = node.mesh.surface_get_material(s)
			if not (material is SpatialMaterial) or material.albedo_texture == null:
				continue
			var texture: Texture = material.albedo_texture
			if not imported_flags.has(texture):
				imported_flags[texture] = texture.flags
			var flags: int = imported_flags[texture]
			if frond_like:
				flags &= ~Texture.FLAG_MIPMAPS
				if material.params_use_alpha_scissor:
					flags &= ~Texture.FLAG_REPEAT
			if flags != texture.flags:
				texture.flags = flags
				changed += 1
	return changed


func _read_jobs() -> Array:
	var jobs := []
	var f := File.new()
	if f.open(JOBS, File.READ) != OK:
		printerr("inspect.gd: no ", JOBS)
		return jobs
	while not f.eof_reached():
		var line := f.get_line()
		if line.strip_edges() == "":
			continue
		var p := line.split("\t")
		var bounds := []
		if p.size() > 5 and p[5].strip_edges() != "":
			for v in p[5].split(","):
				bounds.append(float(v))
		var times := []
		if p.size() > 3:
			times = Array(p[3].split(" ", false))
		if times.empty():
			times = ["0"]
		jobs.append({
			"name": p[0], "res": p[1], "out": p[2], "times": times,
			"clip": p[4] if p.size() > 4 else "",
			"bounds": bounds,
			"vat": p[6].strip_edges() if p.size() > 6 else "",
		})
	f.close()
	return jobs


func _read_imports() -> Dictionary:
	var out := {}
	var f := File.new()
	if f.open(IMPORTS, File.READ) != OK:
		return out
	while not f.eof_reached():
		var line := f.get_line()
		if line.strip_edges() == "":
			continue
		var parsed := JSON.parse(line)
		if parsed.error == OK and parsed.result is Dictionary and parsed.result.has("res"):
			out[parsed.result["res"]] = parsed.result
	f.close()
	return out


func _make_stage() -> void:
	stage = Spatial.new()
	stage.name = "Stage"
	root.add_child(stage)
	var env := Environment.new()
	env.background_mode = Environment.BG_COLOR
	env.background_color = BACKGROUND
	env.ambient_light_color = Color(1, 1, 1)
	env.ambient_light_energy = 0.4
	env.tonemap_mode = Environment.TONE_MAPPER_LINEAR
	var world_env := WorldEnvironment.new()
	world_env.environment = env
	stage.add_child(world_env)
	var light := DirectionalLight.new()
	light.light_energy = 1.0
	light.shadow_enabled = false
	stage.add_child(light)
	# From above, front and right, like a sun.
	light.look_at_from_position(Vector3(1, 2, 1.5), Vector3.ZERO, Vector3.UP)
	camera = Camera.new()
	camera.fov = FOV_Y
	camera.keep_aspect = Camera.KEEP_HEIGHT
	stage.add_child(camera)
	camera.current = true


# Everything below `node`, depth first.
func _all(node: Node, out: Array) -> Array:
	out.append(node)
	for child in node.get_children():
		_all(child, out)
	return out


func _describe(scene: Node, record: Dictionary) -> void:
	var skeletons := []
	var players := []
	var meshes := []
	var aabb := AABB()
	var have_aabb := false
	for node in _all(scene, []):
		var path := str(scene.get_path_to(node))
		if node is Skeleton:
			skeletons.append({"path": path, "bones": node.get_bone_count(), "visible": node.is_visible_in_tree()})
		elif node is AnimationPlayer:
			var anims := []
			for anim_name in node.get_animation_list():
				var anim: Animation = node.get_animation(anim_name)
				anims.append({
					"name": anim_name,
					"length": anim.length,
					"tracks": anim.get_track_count(),
					"loop": anim.loop,
					"step": anim.step,
					"keys": _key_count(anim),
				})
			players.append({"path": path, "animations": anims, "autoplay": node.autoplay})
		elif node is MeshInstance:
			var mesh: Mesh = node.mesh
			var entry := {
				"path": path,
				"visible": node.is_visible_in_tree(),
				"skeleton": str(node.skeleton),
				"skinned": node.skin != null,
				"surfaces": mesh.get_surface_count() if mesh else 0,
				"materials": [],
			}
			if mesh:
				var vertices := 0
				for s in range(mesh.get_surface_count()):
					var material: Material = node.get_surface_material(s)
					if material == null:
						material = mesh.surface_get_material(s)
					entry["materials"].append(_material(material))
					vertices += mesh.surface_get_array_len(s)
				entry["vertices"] = vertices
				var box: AABB = node.global_transform.xform(mesh.get_aabb())
				aabb = box if not have_aabb else aabb.merge(box)
				have_aabb = true
			meshes.append(entry)
	record["nodes"] = _all(scene, []).size()
	record["skeletons"] = skeletons
	record["animation_players"] = players
	record["meshes"] = meshes
	if have_aabb:
		record["aabb"] = {"min": _v(aabb.position), "max": _v(aabb.end)}


func _key_count(anim: Animation) -> int:
	var n := 0
	for t in range(anim.get_track_count()):
		n += anim.track_get_key_count(t)
	return n


func _material(material: Material) -> Dictionary:
	if material == null:
		return {"class": null}
	var out := {
		"class": material.get_class(),
		"name": material.resource_name,
		"resource_path": material.resource_path,
	}
	if material is SpatialMaterial:
		out["alpha_scissor"] = material.params_use_alpha_scissor
		out["alpha_scissor_threshold"] = material.params_alpha_scissor_threshold
		out["transparent"] = material.flags_transparent
		out["depth_draw_mode"] = material.params_depth_draw_mode
		out["cull_mode"] = ["back", "front", "disabled"][material.params_cull_mode]
		out["unshaded"] = material.flags_unshaded
		out["albedo_color"] = [material.albedo_color.r, material.albedo_color.g, material.albedo_color.b, material.albedo_color.a]
		out["albedo_texture"] = material.albedo_texture != null
		if material.albedo_texture:
			out["albedo_texture_size"] = [material.albedo_texture.get_width(), material.albedo_texture.get_height()]
			out["albedo_texture_flags"] = material.albedo_texture.flags
		out["normal_enabled"] = material.normal_enabled
		out["normal_texture"] = material.normal_texture != null
		out["roughness_texture"] = material.roughness_texture != null
		out["metallic_texture"] = material.metallic_texture != null
	elif material is ShaderMaterial:
		out["shader"] = material.shader.resource_path if material.shader else null
	return out


func _pose(scene: Node, clip: String, time: float) -> Dictionary:
	var out := {"time": time, "clip": null}
	for node in _all(scene, []):
		if node is AnimationPlayer:
			var names: PoolStringArray = node.get_animation_list()
			if names.empty():
				continue
			var name := clip
			if name == "" or not node.has_animation(name):
				name = names[0]
			node.play(name)
			node.seek(time, true)
			node.stop(false)
			out["clip"] = name
			out["player"] = str(scene.get_path_to(node))
			break
	return out


func _frame(bounds: Array, record: Dictionary) -> Dictionary:
	var lo: Vector3
	var hi: Vector3
	var source := "frond"
	if bounds.size() == 6:
		lo = Vector3(bounds[0], bounds[1], bounds[2])
		hi = Vector3(bounds[3], bounds[4], bounds[5])
	elif record.has("aabb"):
		lo = Vector3(record["aabb"]["min"][0], record["aabb"]["min"][1], record["aabb"]["min"][2])
		hi = Vector3(record["aabb"]["max"][0], record["aabb"]["max"][1], record["aabb"]["max"][2])
		source = "godot_aabb"
	else:
		lo = Vector3(-1, -1, -1)
		hi = Vector3(1, 1, 1)
		source = "unit"
	var azimuth := deg2rad(float(_env("FROND_GODOT_AZIMUTH", "0")))
	var elevation := deg2rad(float(_env("FROND_GODOT_ELEVATION", "10")))
	var target := (lo + hi) * 0.5
	var radius: float = max((hi - lo).length() * 0.5, 1e-3)
	var distance := radius / sin(deg2rad(FOV_Y * 0.5))
	var direction := Vector3(cos(elevation) * sin(azimuth), sin(elevation), cos(elevation) * cos(azimuth))
	var up := Vector3(-sin(elevation) * sin(azimuth), cos(elevation), -sin(elevation) * cos(azimuth))
	# Depth range: the bounds' sphere with room for the wind to move the tree out of it.
	camera.near = max(distance - radius * 2.0, distance * 1e-3)
	camera.far = distance + radius * 2.0
	camera.look_at_from_position(target + direction * distance, target, up)
	return {
		"bounds_from": source,
		"target": _v(target),
		"distance": distance,
		"fov_y": FOV_Y,
		"azimuth_deg": rad2deg(azimuth),
		"elevation_deg": rad2deg(elevation),
		"background": [BACKGROUND.r, BACKGROUND.g, BACKGROUND.b],
	}


func _env(name: String, default: String) -> String:
	var value := OS.get_environment(name)
	return value if value != "" else default


func _v(v: Vector3) -> Array:
	return [v.x, v.y, v.z]
