"""Pinocchio: the driven session (:mod:`.driven`) over its model (:mod:`.model`), its
settings (:mod:`.settings`) and the released session (:mod:`.free`)."""
