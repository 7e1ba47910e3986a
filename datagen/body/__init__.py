"""The SMPL-format body model: posing (numpy and torch), files, subdivision, shapes and the Anny-derived default."""
