//! Small reverse-mode autodiff over f32 matrices: MLP, LSTM with BPTT, Adam, safetensors.
