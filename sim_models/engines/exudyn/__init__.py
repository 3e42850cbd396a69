"""Exudyn: the driven session (:mod:`.driven`: start, stepping) in phases, the model
(:mod:`.model`) and the readout (:mod:`.readout`), with planar helpers (:mod:`.planar`);
its settings (:mod:`.settings`) and the released session (:mod:`.free`)."""
