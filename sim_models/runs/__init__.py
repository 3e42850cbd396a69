"""The runs of the engines: a driven run of any registered engine by name (:mod:`.driven`),
a released one (:mod:`.free`), the sampling plan and step schedule (:mod:`.sampling`), the
recorder and the run record (:mod:`.engine_run`), the free run's record
(:mod:`.free_run`), the Newton-Euler readout (:mod:`.newton_euler`), the arithmetic's
error floor (:mod:`.precision`) and the speed studies' step rate (:mod:`.timing`)."""
