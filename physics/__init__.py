"""Physics core of the spur-gear wear model (numpy/scipy only; never imports torch).

Subpackages in the order of the data flow, each importing only from those before it:
``gear`` (geometry, kinematics, Hertz, tooth, mesh stiffness, FE check, load sharing; thesis
2.1-2.3, 3.1-3.2), ``tribology`` (lubrication, mixed-EHL solver and its table, flash
temperature, contact state, wear; 2.4-2.6), ``dynamics`` (torsional model, wear/dynamics
coupling; 3.3-4.1), ``signals`` (features, order analysis, measurement chain; 4.2),
``estimators`` (empirical inverse; 4.4), ``dataset``, ``reproduce`` and ``loop`` (the apps and
what they run), ``testbeds`` (the synthetic and independent bundle makers for trying the loop
and the surrogate without measurements; not imported by the product). ``params`` (validated
parameters), ``scope`` (the model's operating scope), ``command`` and ``files`` serve them all.
Each subpackage names its public API in ``__all__``. Importing the package changes no process
state: each app installs its Ctrl-C and SIGTERM handlers itself when it starts
(:func:`physics.interrupt.install_at_start`).
"""
