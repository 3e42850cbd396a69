"""MuJoCo Warp (the MuJoCo model in float32 Warp kernels): the driven session and its
stepping (:mod:`.driven`), its settings (:mod:`.settings`) and the released session
(:mod:`.free`)."""
