"""Text in result files: CF §2.2 allows char arrays, not netCDF-4 variable-length strings,
and a coordinate variable must be numeric (CF §5). The real CF checker needs UDUNITS-2,
which CI lacks, so these rules are checked here on the file as written."""

import netCDF4
import numpy as np
import xarray as xr

from slipcycle.io.metadata import cf_complete, cf_problems


def _dataset_with_text() -> xr.Dataset:
    return xr.Dataset(
        {"slip": (("node", "component"), np.ones((3, 2)), {"units": "m"}),
         "state": ("node", np.array(["stick", "slip", "separation"]))},
        coords={"node": np.arange(3), "component": ["t1", "t2"]})


def test_uncompleted_text_is_reported_as_a_cf_problem():
    problems = cf_problems(_dataset_with_text())
    assert any(p.startswith("state: text stored as variable-length") for p in problems)


def test_completed_text_is_written_as_char_arrays_and_read_back_unchanged(tmp_path):
    ds = cf_complete(_dataset_with_text())
    assert cf_problems(ds) == []
    path = tmp_path / "r.nc"
    ds.to_netcdf(path)
    with netCDF4.Dataset(path) as f:
        for name, var in f.variables.items():
            assert var.dtype is not str, f"{name} is a variable-length string"
            if name in f.dimensions:
                assert var.ndim == 1 and var.dtype.kind in "iuf", name
    with xr.open_dataset(path) as back:
        assert cf_problems(back) == []
        assert list(back["state"].values) == ["stick", "slip", "separation"]
        assert list(back["component_name"].values) == ["t1", "t2"]
        assert list(back["component"].values) == [0, 1]
        np.testing.assert_array_equal(back["slip"].values, ds["slip"].values)
