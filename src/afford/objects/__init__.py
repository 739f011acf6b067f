"""A world model made of objects, beside the paper's EM*D pathway (paper II.C).

The paper predicts the next state image from a latent code; here the state is the set of
objects itself, and each part of the paper's pathway has its counterpart:

- E, perceiving: the objects seen in a state image (kind, pose, held);
- P^a, one dynamics net per affordance type (`dynamics.py`), over the set of objects;
- eq. (2), c' = c + dc: each object's next state is its state plus a predicted change, and an
  object the net's gate calls still is copied exactly;
- eq. (3): only the objects that move change; every other object stays as it was.

`state.py` turns true poses into the nets' features and back; `transitions.py` reads
(state, action, next state) examples from any dataset's poses; `train.py` and `measure.py`
train and measure the dynamics.
"""
