"""PyBullet: the driven session (:mod:`.driven`) and the released one (:mod:`.free`)."""
