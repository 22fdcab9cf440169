tool
extends EditorPlugin
# Imports models with Godot 3's own editor importer (default import settings), one file at a
# time, and records for each what Godot printed while importing it.
#
# res://frond_import.txt lists the files, one a line: "<absolute source path>\t<res:// path>".
# Each is copied into the project and the editor's filesystem rescanned, which imports it; once
# its .import file exists, the ERROR / WARNING entries Godot printed meanwhile are kept (read back
# from its stderr, see frond_log.gd). Then res://frond_import_result.txt gets one JSON line per
# file and a last line {"done": true}:
#   {"res": "res://...", "imported": true, "import_ms": 812, "log": [{"text": "...", "count": 3}]}
# and the editor is ended by killing it: Godot 3.2.3's editor ignores --quit, and after importing
# an animated glTF it hangs in get_tree().quit() (frond's files and Blender's alike).

const Log := preload("res://frond_log.gd")
const LIST := "res://frond_import.txt"
const RESULT := "res://frond_import_result.txt"
const PER_FILE_TIMEOUT_MS := 300000

var jobs := []
var current := -1
var idle := 0
var frames := 0
var started_ms := 0
var log_offset := 0
var results := []


func _enter_tree() -> void:
	var f := File.new()
	if f.open(LIST, File.READ) != OK:
		printerr("frond_import: no ", LIST, "; nothing to import")
		return
	while not f.eof_reached():
		var line := f.get_line().strip_edges()
		if line == "":
			continue
		var parts := line.split("\t")
		jobs.append({"src": parts[0], "res": parts[1]})
	f.close()
	printerr("frond_import: %d file(s) to import" % jobs.size())


func _process(_delta: float) -> void:
	if jobs.empty():
		return
	frames += 1
	var fs := get_editor_interface().get_resource_filesystem()
	if fs.is_scanning():
		idle = 0
		return
	idle += 1
	# The editor scans res:// once at start; let that settle before the first copy.
	if current < 0:
		if frames >= 5 and idle >= 3:
			_next(fs)
		return
	var job: Dictionary = jobs[current]
	var done := File.new().file_exists(job["res"] + ".import")
	var timed_out := OS.get_ticks_msec() - started_ms > PER_FILE_TIMEOUT_MS
	if (done and idle >= 2) or timed_out:
		var record := {
			"res": job["res"],
			"imported": done,
			"import_ms": OS.get_ticks_msec() - started_ms,
			"log": Log.entries(log_offset),
		}
		results.append(record)
		_next(fs)


func _next(fs: EditorFileSystem) -> void:
	current += 1
	if current >= jobs.size():
		var out := File.new()
		out.open(RESULT, File.WRITE)
		for record in results:
			out.store_line(to_json(record))
		out.store_line(to_json({"done": true}))
		out.close()
		jobs = []
		printerr("frond_import: done, ending the editor")
		OS.kill(OS.get_process_id())
		return
	var job: Dictionary = jobs[current]
	var dir := Directory.new()
	dir.make_dir_recursive(job["res"].get_base_dir())
	log_offset = Log.size()
	printerr("frond_import: importing ", job["res"])
	var err := dir.copy(job["src"], job["res"])
	if err != OK:
		var text := "frond_import: cannot copy %s (error %d)" % [job["src"], err]
		printerr(text)
		results.append({"res": job["res"], "imported": false, "import_ms": 0, "log": [{"text": text, "count": 1}]})
		_next(fs)
		return
	started_ms = OS.get_ticks_msec()
	idle = 0
	fs.scan()
