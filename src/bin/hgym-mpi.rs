// `hgym-mpi`: the `hgym` command line (src/main.rs), one process per MPI rank (the `mpi`
// feature; see `hgym::flow::ranks`). Built by `make mpi`.

include!("../main.rs");
