"""The engine models built from a linkage: the compiled linkage (:mod:`.tree`), the MuJoCo
model (:mod:`.mjcf`), the URDF and its loop closures (:mod:`.urdf`), how numbers are written
into model files (:mod:`.model_numbers`), the viewer's model (:mod:`.viewer_model`), the
released variants of the cases (:mod:`.free_cases`) and the committed model files
(:mod:`.model_files`, written into ``sim_models/models/``)."""
