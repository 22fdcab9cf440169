extends SceneTree
# Compiles Godot 3 shaders (.shader, shader_type spatial) headless and prints one JSON line per
# file with what Godot said:
#   {"shader": "/abs/x.shader", "mode": "spatial", "params": ["vat_position", ...],
#    "log": [{"text": "...", "count": 1}], "ok": true}
#
# Run by check_shaders.sh:  godot3 --path PROJECT -s res://check_shader.gd
# FROND_GODOT_SHADERS: the shader files, separated by ':'. FROND_GODOT_LOG: where Godot's stderr
# goes (frond_log.gd reads the errors back from it).
#
# Two stages, both of which print errors to stderr and nowhere else:
# 1. Godot's shader language: the code is set on a Shader and its uniform list requested, which
#    makes the rasterizer parse and translate it at once (syntax, types, unknown built-ins,
#    render_mode / hint names). Errors print as "SHADER ERROR: (line): message" plus the code.
# 2. The GLSL Godot generates, compiled by the GL driver (llvmpipe here): that happens only when
#    something is drawn with it, so each shader is put on a quad in front of the camera and two
#    frames are rendered. Driver errors print as "ERROR: ... _display_error_with_code" / "program
#    compilation failed". Only the variant drawn (no shadows, not skinned) is compiled.
# "ok" is true when neither stage printed an ERROR / SHADER ERROR.

const Log := preload("res://frond_log.gd")


func _init() -> void:
	call_deferred("_run")


func _run() -> void:
	var camera := Camera.new()
	root.add_child(camera)
	camera.current = true
	var light := DirectionalLight.new()
	root.add_child(light)
	for path in OS.get_environment("FROND_GODOT_SHADERS").split(":", false):
		var offset := Log.size()
		var record := {"shader": path}
		var f := File.new()
		if f.open(path, File.READ) != OK:
			record["ok"] = false
			record["log"] = [{"text": "cannot read " + path, "count": 1}]
			print(to_json(record))
			continue
		var shader := Shader.new()
		shader.code = f.get_as_text()
		f.close()
		record["mode"] = ["spatial", "canvas_item", "particles"][shader.get_mode()]
		var params := []
		for p in VisualServer.shader_get_param_list(shader.get_rid()):
			params.append(p["name"])
		record["params"] = params
		if shader.get_mode() == Shader.MODE_SPATIAL:
			var quad := MeshInstance.new()
			quad.mesh = QuadMesh.new()
			var material := ShaderMaterial.new()
			material.shader = shader
			quad.material_override = material
			# In front of the camera, and never culled whatever the vertex shader does.
			quad.translation = Vector3(0, 0, -2)
			quad.extra_cull_margin = 16384.0
			root.add_child(quad)
			for _i in range(2):
				yield(VisualServer, "frame_post_draw")
			root.remove_child(quad)
			quad.free()
		var entries := Log.entries(offset)
		var ok := true
		for e in entries:
			if e["text"].begins_with("ERROR") or e["text"].begins_with("SHADER ERROR") or e["text"].begins_with("**ERROR"):
				ok = false
		record["log"] = entries
		record["ok"] = ok
		print(to_json(record))
	quit()
