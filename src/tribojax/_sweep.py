"""Parameter sweeps: one model, many inputs, vmapped and sharded across devices (`jax.sharding`).

`sweep(fn, batch)` places the batch on a one-axis device mesh, `NamedSharding(Mesh(devices,
("batch",)), P("batch"))`, runs one jitted `jax.vmap` per device on its slice (dispatched
asynchronously; the members are independent, so nothing is communicated) and assembles global
arrays with the same sharding (docs/architecture.md says why not one partitioned jit). The batch
is padded to a multiple of the device count by repeating its last member (a valid input, so no
check fires on padding) and the padding is cut off again.

Several CPU devices for tests: `XLA_FLAGS=--xla_force_host_platform_device_count=N` set before JAX
initialises. GPUs and multi-host setups use the same code through JAX's own runtime.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding
from jax.sharding import PartitionSpec as P

from ._checks import as_f64, cacheable_call, mode_jit
from ._precision import ensure_x64


def product_grid(**axes) -> dict:
    """All combinations of the given 1-D axes, flattened: {name: array of length Π len(axis)}.

    `product_grid(D=Ds, G=Gs, load=loads)` gives len(Ds)·len(Gs)·len(loads) members, the last
    axis varying fastest (C order). A scalar is a fixed value, broadcast to every member.
    """
    ensure_x64()
    arrays = {k: jnp.atleast_1d(as_f64(v, k)) for k, v in axes.items()}
    for k, v in arrays.items():
        if v.ndim != 1 or v.shape[0] == 0:
            raise ValueError(f"axis {k} must be a non-empty 1-D array or a scalar, got {v.shape}")
    grids = jnp.meshgrid(*arrays.values(), indexing="ij")
    return {k: g.ravel() for k, g in zip(arrays, grids)}


@mode_jit
def _vmapped(fn, batch):
    return jax.vmap(fn)(batch)


def sweep(fn, batch, *, devices=None):
    """`jax.vmap(fn)(batch)`, with the batch sharded across `devices` (default all).

    Args:
        fn: a function of one member (e.g. a dict of scalars) returning a pytree of arrays; an
            `equinox.Module` such as `tribojax.LoopChain` is traced (its arrays are not baked in).
        batch: pytree of arrays sharing the leading (batch) axis, e.g. from `product_grid`.
        devices: a sequence of JAX devices; `jax.devices()[:1]` runs unsharded on one device.
    Returns:
        The pytree of outputs with the batch axis leading, sharded over the devices along it when
        the batch size is a multiple of their number (otherwise after the cut of the padding,
        wherever XLA places it). Values equal those of an unsharded `jax.vmap` (the members are
        independent).
    """
    ensure_x64()
    leaves = jax.tree.leaves(batch)
    if not leaves:
        raise ValueError("batch is empty: give a pytree of arrays with a leading batch axis")
    leaves = [jnp.asarray(x) for x in leaves]
    n = leaves[0].shape[0] if leaves[0].ndim else 0
    if n == 0 or any(x.ndim == 0 or x.shape[0] != n for x in leaves):
        shapes = [tuple(x.shape) for x in leaves]
        raise ValueError(f"every batch array needs the same non-zero leading length, got {shapes}")
    devices = jax.devices() if devices is None else list(devices)
    if not devices:
        raise ValueError("devices must name at least one device")
    sharding = NamedSharding(Mesh(np.array(devices), ("batch",)), P("batch"))
    pad = (-n) % len(devices)

    def place(x):
        x = jnp.asarray(x)
        if pad:
            x = jnp.concatenate([x, jnp.repeat(x[-1:], pad, axis=0)])
        return jax.device_put(x, sharding)

    placed = jax.tree.map(place, batch)
    parts = [
        jax.tree.map(lambda x, d=device: _shard_on(x, d), placed)
        for device in sharding.mesh.devices.flat
    ]
    # all parts dispatched before any is checked (cacheable_call: one program without host
    # callbacks per part; a non-finite output runs them again with the raising checks)
    local = cacheable_call(lambda f, ps: [_vmapped(f, p) for p in ps], fn, parts)
    total = n + pad

    def assemble(*parts):
        shape = (total,) + parts[0].shape[1:]
        return jax.make_array_from_single_device_arrays(shape, sharding, list(parts))

    out = jax.tree.map(assemble, *local)
    return jax.tree.map(lambda x: x[:n], out) if pad else out


def _shard_on(x, device):
    (shard,) = [s for s in x.addressable_shards if s.device == device]
    return shard.data
