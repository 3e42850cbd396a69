"""MuJoCo: the driven session (:mod:`.driven`), the released one (:mod:`.free`), the
scene variants (:mod:`.scene`)."""
