//! Online learners over OIESGP experts (DS, GS, DU, GU) and their novelty scores.

pub mod evt;
