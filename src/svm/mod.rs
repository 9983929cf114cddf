pub mod kernel_svm;
