seed   s-       static   m-       moving   ate_movers ate_static imm7_static ratio
