"""The same sweep on a Dask cluster (a LocalCluster of two worker processes) gives the local table, bit for bit."""

import pandas as pd
import pytest

from kilnctl.sweep import Grid, LatinHypercube, Study, Uniform

distributed = pytest.importorskip("distributed", reason="the Dask executor needs 'distributed' (kilnctl[sweep])")


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=40) as cluster, distributed.Client(cluster) as c:
        yield c


def test_dask_client_gives_the_local_table(client, tmp_path):
    st = Study(LatinHypercube({"m_v": Uniform(240e3, 974e3), "ramp_rate": Uniform(37.0, 148.0)}, n=6, seed=2),
               outputs=["peak_current_A", "final_current_A", "n_events"], model="macro", t_end=12.0)
    local = st.run(executor="serial", progress=False)
    on_dask = st.run(executor=client, cache=tmp_path / "cache", progress=False)
    assert on_dask.info["executor"].startswith("dask")
    cols = list(st.variables) + list(st.outputs)
    pd.testing.assert_frame_equal(local.table[cols], on_dask.table[cols], check_exact=True)
    assert not client.status == "closed"  # a client the caller gave stays open


def test_dask_address_string(client):
    st = Study(Grid({"m_v": [300e3, 600e3]}), outputs=["peak_current_A"], model="macro", t_end=5.0)
    address = client.scheduler.address.replace("tcp://", "dask://")
    res = st.run(executor=address, progress=False)
    ref = st.run(executor="serial", progress=False)
    assert res.table["peak_current_A"].tolist() == ref.table["peak_current_A"].tolist()
