"""GA-RBF learned inverse kinematics, as a seed for numerical IK (METHODS.md section 6).

A Gaussian RBF network (:mod:`.rbf`) maps an encoded pose (:mod:`.encoding`) to the joints of one
configuration branch (:mod:`.branch`); a genetic algorithm (:mod:`.tuning`, DEAP) chooses its
structure; :mod:`.network` trains it, checks every query against the trained domain and starts
damped least squares from it. Files: :mod:`robocal.io.ik_network`.
"""

from .branch import ConfigurationBranch, default_branch, joint_box_branch, on_branch, reference_model, sample_branch
from .encoding import ENCODING, encode_poses
from .network import (
    IKSeedNetwork,
    NetworkMismatchError,
    SeedPrediction,
    ik_with_seed_network,
    train_ik_network,
)
from .rbf import RBFNetwork, fit_rbf
from .tuning import DEFAULT_STRUCTURE, Structure, tune_structure

__all__ = ["ConfigurationBranch", "DEFAULT_STRUCTURE", "ENCODING", "IKSeedNetwork", "NetworkMismatchError",
           "RBFNetwork", "SeedPrediction", "Structure", "default_branch", "encode_poses", "fit_rbf",
           "ik_with_seed_network", "joint_box_branch", "on_branch", "reference_model", "sample_branch", "train_ik_network",
           "tune_structure"]
