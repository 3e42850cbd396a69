"""MuJoCo Warp (the MuJoCo model in float32 Warp kernels): the driven session
(:mod:`.driven`) and the released one (:mod:`.free`)."""
