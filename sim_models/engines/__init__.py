"""The engines behind one protocol: the driven session (:mod:`.protocol`), the released one
(:mod:`.free_protocol`; its force elements :mod:`.free_elements`), the settings base
(:mod:`.settings`) and every setting's range (:mod:`.ranges`), the registry
(:mod:`.registry`), and one folder per engine (``mujoco/``, ``pybullet/``, ``exudyn/``,
``pinocchio/``, ``mujoco_warp/``), each with its driven session (``driven.py``) and its
released one (``free.py``).  No engine folder imports another's except where one engine is
built on another (MuJoCo Warp on MuJoCo: ``tests/test_architecture.py``)."""
