"""The worked solutions of ``xval explain``, in the course notes' method.

Modules:

* :mod:`reports.explain.blocks`: The pieces a worked solution is made of, independent of the
  output format.
* :mod:`reports.explain.doc`: Assemble the worked solution of one configuration (``xval
  explain``).
* :mod:`reports.explain.draw`: The vector polygon drawn as the notes draw it: each r_k an
  arrow from tail to tip, named, with its angle theta_k marked counter-clockwise from +x at
  its tail.
* :mod:`reports.explain.forces`: Kinetostatics in the notes' way: inertia forces and moments
  (d'Alembert), the offset e = I alpha / (m a_G) of the resultant inertia force, the
  equilibrium equations of every moving body, the joint forces, and the motor's torque and
  power with the power balance as the check.
* :mod:`reports.explain.kin`: Loop-by-loop kinematics in the notes' order: polygon, loop
  equation, position table, first variable table, velocity equation and its elimination,
  velocity table, second variable table, acceleration equation and its elimination,
  acceleration table, and the solver's matrix-method values beside the hand ones.
* :mod:`reports.explain.loops`: The notes' vector polygons of a linkage, and its unknowns
  loop by loop.
* :mod:`reports.explain.notes`: Where the course notes' printed figures come from, for the
  notes' own examples.
* :mod:`reports.explain.numbers`: The numbers of the worked solutions: significant digits
  (:func:`digits`, :func:`num`), the printed values (:func:`fmt`, never a false 0), and the
  check that every 'calc:' line gives the value printed beside it (:func:`reproduces`,
  :func:`build_checked`).
* :mod:`reports.explain.position`: Position analysis of one loop by hand: the two unknowns
  from the loop equation.
* :mod:`reports.explain.printing`: How the worked solutions' expressions print: the notes'
  LaTeX, plain text and MathML printers of the printing nodes (:mod:`reports.explain.sym`),
  and their evaluation (:func:`value`, :func:`to_plain`).
* :mod:`reports.explain.render`: Write a worked solution as Markdown, HTML or LaTeX.
* :mod:`reports.explain.sym`: SymPy vocabulary of the worked solutions: the notes' symbols
  and the printing nodes (printed by :mod:`reports.explain.printing`; the numbers in them
  and the check of the printed values: :mod:`reports.explain.numbers`).
* :mod:`reports.explain.terms`: Terms of the velocity and acceleration equations, and the
  notes' elimination.
"""
