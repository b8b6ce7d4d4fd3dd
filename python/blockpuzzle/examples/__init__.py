"""Runnable examples that travel in the wheel (``python -m blockpuzzle.examples.NAME``):

* ``sb3_td3``: Stable-Baselines3 TD3 on a BlockPuzzle task with the paper's curriculum (needs
  ``pip install stable-baselines3``, which brings torch); ``--help`` lists its options.
"""
