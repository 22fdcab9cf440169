tool
extends Reference
# What Godot printed: run.sh sends Godot's stderr to a file and names it in FROND_GODOT_LOG; the
# scripts read it back to attach the ERROR / WARNING entries to the file being worked on. (Godot
# 3.2's own file logging is off in the editor and would not see the import, hence stderr.)


static func path() -> String:
	return OS.get_environment("FROND_GODOT_LOG")


# Bytes in the log so far: the offset to pass to `entries` later.
static func size() -> int:
	var f := File.new()
	if path() == "" or f.open(path(), File.READ) != OK:
		return 0
	var n := f.get_len()
	f.close()
	return n


static func is_problem(line: String) -> bool:
	for prefix in ["ERROR:", "WARNING:", "SCRIPT ERROR:", "SHADER ERROR:", "**ERROR**", "**WARNING**", "**SCRIPT ERROR**"]:
		if line.begins_with(prefix):
			return true
	return false


# The ERROR / WARNING entries written after byte `from`, each joined to its "At:" line, repeated
# entries counted once: [{"text": "ERROR: ... | At: ...", "count": 3}, ...].
static func entries(from: int) -> Array:
	var f := File.new()
	if path() == "" or f.open(path(), File.READ) != OK:
		return [{"text": "frond: Godot's log (FROND_GODOT_LOG=%s) is not readable" % path(), "count": 1}]
	var n := f.get_len()
	f.seek(from)
	var text := f.get_buffer(n - from).get_string_from_utf8()
	f.close()
	var lines := text.split("\n")
	var found := []
	var index := {}
	var i := 0
	while i < lines.size():
		var line: String = lines[i]
		if is_problem(line):
			var entry := line
			if i + 1 < lines.size() and lines[i + 1].strip_edges().begins_with("At:"):
				entry += " | " + lines[i + 1].strip_edges()
				i += 1
			if index.has(entry):
				found[index[entry]]["count"] += 1
			else:
				index[entry] = found.size()
				found.append({"text": entry, "count": 1})
		i += 1
	return found
