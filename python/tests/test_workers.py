"""brume in the places a training pipeline puts it: forked worker processes (a PyTorch
DataLoader's, multiprocessing's default on Linux), pickled transforms (spawned workers),
torchvision v2's dict samples, PIL images and albumentations' Compose."""

import multiprocessing
import pickle
import sys

import numpy as np
import pytest

import brume
from brume.augment import RandomFog

H, W = 48, 64


@pytest.fixture(scope="module")
def sample():
    rng = np.random.default_rng(11)
    image = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    y, x = np.mgrid[0:H, 0:W]
    range_m = (5.0 + 200.0 * x / (W - 1) + 0.5 * y).astype(np.float32)
    return image, range_m


def _fog_in_child(args):
    """Runs in a forked worker: the module's renderer, a renderer of the parent's, a new
    one, and a RandomFog holding the parent's."""
    image, range_m, renderer, transform = args
    return [
        brume.fog(image, range_m, beta=0.02),
        renderer.fog(image, range_m, beta=0.02),
        brume.Renderer().fog(image, range_m, beta=0.02),
        transform(image=image, depth=range_m)["image"],
    ]


@pytest.mark.skipif(sys.platform != "linux", reason="fork() as Linux's multiprocessing does")
def test_forked_workers_render_what_the_parent_renders(sample):
    """The parent renders first (its EGL display, GL thread and CPU pool exist), then forks:
    before, every call in the child waited forever for the parent's threads."""
    image, range_m = sample
    renderer = brume.Renderer()
    expected = brume.fog(image, range_m, beta=0.02)
    np.testing.assert_array_equal(renderer.fog(image, range_m, beta=0.02), expected)
    transform = RandomFog(beta_range=(0.02, 0.02), seed=0, renderer=renderer)
    with multiprocessing.get_context("fork").Pool(2) as pool:
        job = pool.map_async(_fog_in_child, [(image, range_m, renderer, transform)] * 2)
        results = job.get(timeout=120)
    for outputs in results:
        for out in outputs:
            np.testing.assert_array_equal(out, expected)
    # The parent's own renderers still work.
    np.testing.assert_array_equal(renderer.fog(image, range_m, beta=0.02), expected)
    np.testing.assert_array_equal(brume.fog(image, range_m, beta=0.02), expected)


def test_pickled_renderer_is_a_new_one(sample):
    image, range_m = sample
    renderer = brume.Renderer()
    copy = pickle.loads(pickle.dumps(renderer))
    assert isinstance(copy, brume.Renderer) and copy is not renderer
    np.testing.assert_array_equal(
        copy.fog(image, range_m, beta=0.01), renderer.fog(image, range_m, beta=0.01)
    )
    transform = pickle.loads(pickle.dumps(RandomFog(seed=5, renderer=renderer)))
    again = RandomFog(seed=5)
    a, b = transform(image=image, depth=range_m), again(image=image, depth=range_m)
    assert a["beta"] == b["beta"]
    np.testing.assert_array_equal(a["image"], b["image"])


def test_random_fog_takes_a_dict_sample_and_pil_images(sample):
    image, range_m = sample
    by_keywords = RandomFog(seed=2)(image=image, depth=range_m, label=7)
    # torchvision v2's Compose calls transform(sample) with the one dict it was given.
    by_dict = RandomFog(seed=2)({"image": image, "depth": range_m, "label": 7})
    assert by_dict["beta"] == by_keywords["beta"] and by_dict["label"] == 7
    np.testing.assert_array_equal(by_dict["image"], by_keywords["image"])
    Image = pytest.importorskip("PIL.Image")
    pil = RandomFog(seed=2)(image=Image.fromarray(image), depth=range_m)["image"]
    assert isinstance(pil, Image.Image) and pil.size == (W, H)
    np.testing.assert_array_equal(np.asarray(pil), by_keywords["image"])
    given = Image.fromarray(image)
    assert RandomFog(p=0.0)(image=given, depth=range_m)["image"] is given
    with pytest.raises(TypeError, match="needs depth"):
        RandomFog()({"image": image})
    with pytest.raises(TypeError, match="not both"):
        RandomFog()({"image": image}, depth=range_m)


def test_albumentations_fog_follows_the_pipelines_geometry_and_seed(sample):
    A = pytest.importorskip("albumentations")
    from brume.albumentations import Fog

    image, range_m = sample

    def pipeline(**kw):
        return A.Compose(
            [A.HorizontalFlip(p=1.0), Fog(beta_range=(0.005, 0.03), **kw)],
            additional_targets={"depth": "mask"},
            seed=4,
            save_applied_params=True,
        )

    out = pipeline()(image=image, depth=range_m)
    beta = out["applied_transforms"][1][1]["beta"]
    assert 0.005 <= beta <= 0.03
    # The fog read the flipped range: brume.fog of the flipped pair with the β drawn.
    flipped = brume.fog(image[:, ::-1].copy(), range_m[:, ::-1].copy(), beta=beta)
    np.testing.assert_array_equal(out["image"], flipped)
    np.testing.assert_array_equal(out["depth"], range_m[:, ::-1])
    # Compose(seed=…) repeats the draw; the pipeline pickles (spawned workers).
    again = pickle.loads(pickle.dumps(pipeline()))(image=image, depth=range_m)
    np.testing.assert_array_equal(again["image"], out["image"])
    # Masks in the sample go to the fog: the hood stays as it was.
    ego = np.zeros((H, W), bool)
    ego[-6:, 20:40] = True
    masked = A.Compose([Fog(blur=False)], seed=1)(image=image, depth=range_m, ego_mask=ego)
    np.testing.assert_array_equal(masked["image"][ego], image[ego])
    assert not np.array_equal(masked["image"][~ego], image[~ego])
    with pytest.raises(ValueError, match="beta_range"):
        Fog(beta_range=(0.03, 0.005))
    # compat goes to brume.fog as it is.
    fc = A.Compose([Fog(beta_range=(0.02, 0.02), compat="foggy-cityscapes")], seed=1)
    np.testing.assert_array_equal(
        fc(image=image, depth=range_m)["image"],
        brume.fog(image, range_m, beta=0.02, compat="foggy-cityscapes"),
    )
    # airlight_range: a grey drawn from the pipeline's generator, in the applied params.
    grey = pipeline(airlight_range=(0.45, 1.0), blur=False)(image=image, depth=range_m)
    params = grey["applied_transforms"][1][1]
    assert 0.45 <= params["airlight"] <= 1.0
    expected = brume.fog(image[:, ::-1].copy(), range_m[:, ::-1].copy(), beta=params["beta"],
                         airlight=params["airlight"], blur=False)  # fmt: skip
    np.testing.assert_array_equal(grey["image"], expected)
    with pytest.raises(ValueError, match="depth"):
        A.Compose([Fog()])(image=image)


def test_random_fog_draws_other_betas_in_each_torch_worker(sample, monkeypatch):
    """A DataLoader gives each worker a copy of the transform; the copies must not draw the
    same betas. Seeded again from torch's per-worker seed (get_worker_info().seed, the
    documented API, stood in for here by a module of that shape)."""
    import copy
    import types

    image, range_m = sample
    worker = types.SimpleNamespace(id=0, seed=None, num_workers=2)
    fake = types.ModuleType("torch")
    fake.utils = types.SimpleNamespace(
        data=types.SimpleNamespace(get_worker_info=lambda: worker if worker.seed else None)
    )
    monkeypatch.setitem(sys.modules, "torch", fake)

    def betas(transform, seed):
        worker.seed = seed
        return [transform(image=image, depth=range_m)["beta"] for _ in range(3)]

    transform = RandomFog(seed=3, blur=False, refine=False)
    main = betas(copy.deepcopy(transform), None)  # not in a worker: the seed's own draws
    assert main == betas(RandomFog(seed=3, blur=False, refine=False), None)
    first, second = (betas(copy.deepcopy(transform), s) for s in (1000, 1001))
    assert first != second and first != main
    assert betas(copy.deepcopy(transform), 1000) == first  # torch's seed repeats it


def _three_betas(args):
    transform, image, depth = args
    return [transform(image=image, depth=depth)["beta"] for _ in range(3)]


@pytest.mark.skipif(sys.platform != "linux", reason="fork() as Linux's multiprocessing does")
def test_unseeded_random_fog_draws_other_betas_in_each_process(sample):
    """Copies of an unseeded transform in forked processes draw from fresh entropy, not the
    parent's stream again; a seeded one repeats its seed's draws in every process."""
    image, range_m = sample
    for seed, differ in ((None, True), (7, False)):
        transform = RandomFog(seed=seed, blur=False, refine=False)
        with multiprocessing.get_context("fork").Pool(2) as pool:
            jobs = [(transform, image, range_m)] * 2
            first, second = pool.map_async(_three_betas, jobs, chunksize=1).get(120)
        assert (first != second) == differ, (seed, first, second)
