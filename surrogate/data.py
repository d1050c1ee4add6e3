"""The Lightning data module: :class:`surrogate.wear_data.WearData`'s rows served as tensors
(the input scaling and the target's scale of its :class:`~surrogate.schema.FeatureSchema`
applied), in shuffled batches of the training rows and whole for validation and test."""

from __future__ import annotations

import lightning as L
import torch
from torch.utils.data import BatchSampler, DataLoader, RandomSampler, TensorDataset

from surrogate.wear_data import WearData


class WearDataModule(WearData, L.LightningDataModule):
    """:class:`~surrogate.wear_data.WearData` as Lightning reads it (the same settings)."""

    def tensors(self, split: str) -> TensorDataset:
        rows = self.network_rows(split)
        x = self.schema.scale(rows[self.inputs].to_numpy(float))
        y = rows[self.target].to_numpy(float) / self.schema.target_scale
        return TensorDataset(torch.as_tensor(x, dtype=torch.float32),
                             torch.as_tensor(y, dtype=torch.float32))

    def train_dataloader(self) -> DataLoader:
        # the batches of ``shuffle=True`` (same permutation), each taken as one slice of the
        # tensors instead of row by row and stacked
        data, g = self.tensors("train"), torch.Generator().manual_seed(self.seed)
        order = BatchSampler(RandomSampler(data, generator=g), self.batch_size, drop_last=False)
        return DataLoader(data, sampler=order, batch_size=None, generator=g)

    def val_dataloader(self) -> DataLoader:
        return DataLoader(self.tensors("val"), batch_size=4096)

    def test_dataloader(self) -> DataLoader:
        return DataLoader(self.tensors("test"), batch_size=4096)
