"""The shared training loop's helpers."""

import torch
from torch_geometric.data import Batch, Data

from training.loop import batch_samples


def test_batch_samples_counts_graphs_segments_and_rows():
    """The throughput counts samples, not a batch's keys: a PyG batch by its graphs, a dict of
    segments (the garment regressor's and the motion generator's batches) by its first tensor's
    leading size, a tuple by its first tensor's."""
    graphs = Batch.from_data_list([Data(x=torch.zeros(5, 3)) for _ in range(3)])
    segments = {"pose": torch.zeros(7, 60, 24, 3), "trans": torch.zeros(7, 60, 3), "label": torch.zeros(7, 60),
                "detail": torch.zeros(7, 60, 10, 3), "garment": torch.zeros(7)}
    assert batch_samples(graphs) == 3
    assert batch_samples(segments) == 7
    assert batch_samples((torch.zeros(4, 2), torch.zeros(4))) == 4
