"""Models that users bring: where an MJCF or URDF file of a user's own linkage will be read
(empty for now; the next issue fills it)."""
