"""Physics core of the spur-gear wear model (numpy/scipy only; never imports torch).

Modules follow the thesis: ``geometry`` (2.1), ``load_sharing`` (2.2), ``kinematics`` (2.3),
``contact`` (Hertz), ``lubrication`` (2.4), ``thermal`` (2.5), ``contact_state`` (2.1-2.5
coupled), ``wear`` (2.6) and ``reproduce`` (2.7 tables).
"""
