!     umat_user.f: indentify's finite-strain laws as a CalculiX 2.20
!     user material (replaces ccx's stock umat_user.f; build.sh).
!
!     Material name USERHENCKY... (ccx calls umat_user for names that
!     start with USER and passes the rest, HENCKY...). Constants
!     (*USER MATERIAL, CONSTANTS=n), units N, mm, s, MPa:
!       n = 2: E, nu                 Hencky-linear elasticity
!       n = 3: E, nu, eta            Maxwell (eps_dot_v = dev(T)/eta)
!       n = 5: E, nu, K, m, sY       Norton-Hoff (eps_dot_vp =
!              3/2 <(T_eq - sY)/K>^m dev(T)/T_eq)
!     State (*DEPVAR, 6): the viscous strain E_v (11,22,33,12,13,23).
!
!     The law, as crates/laws + crates/fe of indentify apply it under
!     kinematics: Finite (docs/validation-finite-strain.md, Sec. 1):
!       C = 1 + 2 E_GL (E_GL = emec, the Lagrange strain ccx passes
!       under NLGEOM), E = ln(C)/2 (eigen-decomposition of C - 1 by
!       Jacobi rotations, log1p of its eigenvalues: small strains keep
!       their relative precision),
!       T = lambda tr(E - E_v) 1 + 2 mu dev(E - E_v), E_v updated by
!       backward Euler over the increment (the closed form for
!       Maxwell, the radial return for Norton-Hoff: the same
!       equations as indentify's Law::update),
!       S = P : T, P = dE/dE_GL, in the eigenbasis of C
!       S_ij = T_ij (ln c_i - ln c_j)/(c_i - c_j) (1/c_i if equal),
!       the second Piola-Kirchhoff stress ccx expects in stre.
!     The tangent dS/dE_GL (stiff) is a central finite difference of
!     that stress over the six components of E_GL (step 1e-7 of the
!     largest strain + 1e-10), symmetrized: it only sets Newton's
!     rate, not the converged answer.
!
!     ielas = 1 (ccx's linear predictor of a step's first iteration):
!     no viscous flow (dt taken as 0). A failure (C not positive
!     definite, return map without convergence) asks ccx to cut the
!     increment (pnewdt = 0.25).
!
      subroutine umat_user(amat,iel,iint,kode,elconloc,emec,emec0,
     &        beta,xokl,voj,xkl,vj,ithermal,t1l,dtime,time,ttime,
     &        icmd,ielas,mi,nstate_,xstateini,xstate,stre,stiff,
     &        iorien,pgauss,orab,pnewdt,ipkon)
      implicit none
!
      character*80 amat
!
      integer ithermal(*),icmd,kode,ielas,iel,iint,nstate_,mi(*),iorien,
     &  ipkon(*)
!
      real*8 elconloc(*),stiff(21),emec(6),emec0(6),beta(6),stre(6),
     &  vj,t1l,dtime,xkl(3,3),xokl(3,3),voj,pgauss(3),orab(7,*),
     &  time,ttime,pnewdt
!
      real*8 xstate(nstate_,mi(1),*),xstateini(nstate_,mi(1),*)
!
      integer nc,i,k,ierr,kel(4,21),ip(3,3),a,b
      real*8 ev0(6),ev1(6),evd(6),s(6),sp(6),sm(6),e(6),h,dt,
     &  cc(6,6),emax
!
      kel=reshape((/1,1,1,1,1,1,2,2,2,2,2,2,1,1,3,3,2,2,3,3,3,3,3,3,
     &          1,1,1,2,2,2,1,2,3,3,1,2,1,2,1,2,1,1,1,3,2,2,1,3,
     &          3,3,1,3,1,2,1,3,1,3,1,3,1,1,2,3,2,2,2,3,3,3,2,3,
     &          1,2,2,3,1,3,2,3,2,3,2,3/),(/4,21/))
      ip=reshape((/1,4,5,4,2,6,5,6,3/),(/3,3/))
!
      if(amat(1:6).ne.'HENCKY') then
         write(*,*) '*ERROR in umat_user: material ',amat
         write(*,*) '       is not HENCKY... (indentify umat)'
         call exit(201)
      endif
      nc=-kode-100
      if((nc.ne.2).and.(nc.ne.3).and.(nc.ne.5)) then
         write(*,*) '*ERROR in umat_user: HENCKY needs 2 (elastic),'
         write(*,*) '       3 (Maxwell) or 5 (Norton-Hoff) constants;'
         write(*,*) '       got ',nc
         call exit(201)
      endif
      if(nstate_.lt.6) then
         write(*,*) '*ERROR in umat_user: HENCKY needs *DEPVAR 6'
         call exit(201)
      endif
!
      do i=1,6
         ev0(i)=xstateini(i,iint,iel)
      enddo
      dt=dtime
      if(ielas.eq.1) dt=0.d0
!
      call hencky_update(elconloc,nc,emec,ev0,dt,s,ev1,ierr)
      if(ierr.ne.0) then
         pnewdt=0.25d0
         return
      endif
      do i=1,6
         stre(i)=s(i)
         xstate(i,iint,iel)=ev1(i)
      enddo
!
      if(icmd.eq.3) return
!
!     tangent: central differences of S over E_GL; a shear component
!     emec(k), k > 3, moves E_GL(ij) and E_GL(ji) together, hence the
!     1/2 (the stiffness is the fourth-order tensor's component)
!
      emax=0.d0
      do i=1,6
         emax=max(emax,dabs(emec(i)))
      enddo
      h=1.d-7*emax+1.d-10
      do k=1,6
         do i=1,6
            e(i)=emec(i)
         enddo
         e(k)=emec(k)+h
         call hencky_update(elconloc,nc,e,ev0,dt,sp,evd,ierr)
         if(ierr.ne.0) then
            pnewdt=0.25d0
            return
         endif
         e(k)=emec(k)-h
         call hencky_update(elconloc,nc,e,ev0,dt,sm,evd,ierr)
         if(ierr.ne.0) then
            pnewdt=0.25d0
            return
         endif
         do i=1,6
            cc(i,k)=(sp(i)-sm(i))/(2.d0*h)
            if(k.gt.3) cc(i,k)=cc(i,k)/2.d0
         enddo
      enddo
      do k=1,21
         a=ip(kel(1,k),kel(2,k))
         b=ip(kel(3,k),kel(4,k))
         stiff(k)=(cc(a,b)+cc(b,a))/2.d0
      enddo
!
      return
      end
!
!     The stress update of one point: PK2 s(6) and the new viscous
!     strain ev1(6) from the Lagrange strain el(6), the old viscous
!     strain ev0(6) and the time increment dt. ierr = 1: C not
!     positive definite or no convergence of the eigen-decomposition
!     or of the return map.
!
      subroutine hencky_update(c,nc,el,ev0,dt,s,ev1,ierr)
      implicit none
      integer nc,ierr,i,j,k,l
      real*8 c(*),el(6),ev0(6),dt,s(6),ev1(6),w(3),v(3,3),
     &  ep(3),eh(6),ee(6),tr,g2,bk,t(6),tm(3,3),tt(3,3),st(3,3),
     &  th(3,3),sm(3,3),hencky_dlog,x,q,d,xx,
     &  eta,fac,qt
!
      call hencky_principal(el,w,v,ep,eh,ierr)
      if(ierr.ne.0) return
!
      g2=c(1)/(1.d0+c(2))
      bk=c(1)/(3.d0*(1.d0-2.d0*c(2)))
      do i=1,6
         ee(i)=eh(i)-ev0(i)
         ev1(i)=ev0(i)
      enddo
      tr=ee(1)+ee(2)+ee(3)
!     trial deviator 2 mu dev(E - E_v)
      do i=1,6
         t(i)=g2*ee(i)
      enddo
      do i=1,3
         t(i)=t(i)-g2*tr/3.d0
      enddo
      if((nc.eq.3).and.(dt.gt.0.d0)) then
!        Maxwell, backward Euler: s1 = s_tr/(1 + 2 mu dt/eta)
         eta=c(3)
         fac=1.d0/(1.d0+g2*dt/eta)
         do i=1,6
            t(i)=t(i)*fac
            ev1(i)=ev0(i)+dt*t(i)/eta
         enddo
      elseif((nc.eq.5).and.(dt.gt.0.d0)) then
!        Norton-Hoff, radial return: K x + 3 mu dt x^m = qt - sY,
!        T_eq = sY + K x
         qt=0.d0
         do i=1,3
            qt=qt+t(i)**2+2.d0*t(i+3)**2
         enddo
         qt=dsqrt(1.5d0*qt)
         d=qt-c(5)
         if((d.gt.0.d0).and.(qt.gt.0.d0)) then
            call hencky_overstress(c(3),1.5d0*g2*dt,c(4),d,x,ierr)
            if(ierr.ne.0) return
            q=c(5)+c(3)*x
            xx=dt*x**c(4)
            do i=1,6
               ev1(i)=ev0(i)+1.5d0*xx*t(i)/qt
               t(i)=t(i)*q/qt
            enddo
         endif
      endif
      do i=1,3
         t(i)=t(i)+bk*tr
      enddo
!     S = P : T in the eigenbasis of C
      call hencky_unpack(t,tm)
      do i=1,3
         do j=1,3
            tt(i,j)=0.d0
            do k=1,3
               do l=1,3
                  tt(i,j)=tt(i,j)+v(k,i)*tm(k,l)*v(l,j)
               enddo
            enddo
            th(i,j)=hencky_dlog(w(i),w(j))
            st(i,j)=th(i,j)*tt(i,j)
         enddo
      enddo
      do i=1,3
         do j=1,3
            sm(i,j)=0.d0
            do k=1,3
               do l=1,3
                  sm(i,j)=sm(i,j)+v(i,k)*st(k,l)*v(j,l)
               enddo
            enddo
         enddo
      enddo
      s(1)=sm(1,1)
      s(2)=sm(2,2)
      s(3)=sm(3,3)
      s(4)=(sm(1,2)+sm(2,1))/2.d0
      s(5)=(sm(1,3)+sm(3,1))/2.d0
      s(6)=(sm(2,3)+sm(3,2))/2.d0
      return
      end
!
!     The Hencky strain E = ln(C)/2 from the Lagrange strain el (11,22,33,
!     12,13,23, tensor shear): the eigenvalues w of C - 1 = 2 E_GL, the
!     eigenvectors v (columns), ep = ln(1 + w)/2 and eh = E (same order as
!     el); ierr /= 0 if the decomposition fails or C is not positive definite.
!
      subroutine hencky_principal(el,w,v,ep,eh,ierr)
      implicit none
      integer i,ierr
      real*8 el(6),w(3),v(3,3),ep(3),eh(6),am(3,3),hencky_log1p
      ierr=0
      am(1,1)=2.d0*el(1)
      am(2,2)=2.d0*el(2)
      am(3,3)=2.d0*el(3)
      am(1,2)=2.d0*el(4)
      am(2,1)=am(1,2)
      am(1,3)=2.d0*el(5)
      am(3,1)=am(1,3)
      am(2,3)=2.d0*el(6)
      am(3,2)=am(2,3)
      call hencky_jacobi(am,w,v,ierr)
      if(ierr.ne.0) return
      do i=1,3
         if(w(i).le.-1.d0) then
            ierr=1
            return
         endif
         ep(i)=0.5d0*hencky_log1p(w(i))
      enddo
      call hencky_from_principal(v,ep,eh)
      end
!
!     The symmetric 3x3 matrix a of the 6-vector x (11,22,33,12,13,23)
!
      subroutine hencky_unpack(x,a)
      implicit none
      real*8 x(6),a(3,3)
      a(1,1)=x(1)
      a(2,2)=x(2)
      a(3,3)=x(3)
      a(1,2)=x(4)
      a(2,1)=x(4)
      a(1,3)=x(5)
      a(3,1)=x(5)
      a(2,3)=x(6)
      a(3,2)=x(6)
      end
!
!     x >= 0 with k x + a x^m = d (d > 0): Newton from the bracket
!     [0, d/k], bisection when a step leaves it (the Norton-Hoff
!     overstress, as crates/laws' solve_overstress)
!
      subroutine hencky_overstress(k,a,m,d,x,ierr)
      implicit none
      integer ierr,it
      real*8 k,a,m,d,x,lo,hi,f,df,xn
      ierr=0
      lo=0.d0
      hi=d/k
      x=hi
      do it=1,200
         f=k*x+a*x**m-d
         if(f.gt.0.d0) then
            hi=x
         else
            lo=x
         endif
         if(x.gt.0.d0) then
            df=k+a*m*x**(m-1.d0)
         else
            df=k
         endif
         xn=x-f/df
         if((xn.le.lo).or.(xn.ge.hi)) xn=(lo+hi)/2.d0
         if(dabs(xn-x).le.1.d-15*max(dabs(xn),1.d-300)) then
            x=xn
            return
         endif
         x=xn
         if(hi-lo.le.1.d-16*hi) return
      enddo
      ierr=1
      return
      end
!
!     Eigen-decomposition of a symmetric 3x3 matrix a (destroyed):
!     a = v diag(w) v^T, cyclic Jacobi rotations to an off-diagonal
!     below 1e-30 of the Frobenius norm (or zero)
!
      subroutine hencky_jacobi(a,w,v,ierr)
      implicit none
      integer ierr,i,j,p,q,r,sweep
      real*8 a(3,3),w(3),v(3,3),off,fro,theta,tn,cs,sn,app,aqq,apq,
     &  arp,arq,vrp,vrq
      ierr=0
      do i=1,3
         do j=1,3
            v(i,j)=0.d0
         enddo
         v(i,i)=1.d0
      enddo
      fro=0.d0
      do i=1,3
         do j=1,3
            fro=fro+a(i,j)**2
         enddo
      enddo
      do sweep=1,60
         off=a(1,2)**2+a(1,3)**2+a(2,3)**2
         if(off.le.1.d-60*fro.or.off.eq.0.d0) goto 10
         do p=1,2
            do q=p+1,3
               apq=a(p,q)
               if(apq.ne.0.d0) then
                  app=a(p,p)
                  aqq=a(q,q)
                  theta=(aqq-app)/(2.d0*apq)
                  tn=sign(1.d0,theta)/(dabs(theta)
     &               +dsqrt(theta*theta+1.d0))
                  cs=1.d0/dsqrt(tn*tn+1.d0)
                  sn=tn*cs
                  do r=1,3
                     arp=a(r,p)
                     arq=a(r,q)
                     a(r,p)=cs*arp-sn*arq
                     a(r,q)=sn*arp+cs*arq
                  enddo
                  do r=1,3
                     arp=a(p,r)
                     arq=a(q,r)
                     a(p,r)=cs*arp-sn*arq
                     a(q,r)=sn*arp+cs*arq
                  enddo
                  a(p,q)=0.d0
                  a(q,p)=0.d0
                  do r=1,3
                     vrp=v(r,p)
                     vrq=v(r,q)
                     v(r,p)=cs*vrp-sn*vrq
                     v(r,q)=sn*vrp+cs*vrq
                  enddo
               endif
            enddo
         enddo
      enddo
      ierr=1
      return
 10   do i=1,3
         w(i)=a(i,i)
      enddo
      return
      end
!
!     The symmetric tensor v diag(p) v^T as (11,22,33,12,13,23)
!
      subroutine hencky_from_principal(v,p,x)
      implicit none
      integer i,k,a(6),b(6)
      real*8 v(3,3),p(3),x(6)
      data a /1,2,3,1,1,2/
      data b /1,2,3,2,3,3/
      do i=1,6
         x(i)=0.d0
         do k=1,3
            x(i)=x(i)+v(a(i),k)*p(k)*v(b(i),k)
         enddo
      enddo
      return
      end
!
!     ln(1 + x) accurate for small x (Goldberg's correction)
!
      real*8 function hencky_log1p(x)
      implicit none
      real*8 x,u
      u=1.d0+x
      if(u.eq.1.d0) then
         hencky_log1p=x
      else
         hencky_log1p=dlog(u)*x/(u-1.d0)
      endif
      return
      end
!
!     The divided difference (ln c_i - ln c_j)/(c_i - c_j) of
!     c = 1 + w, 1/c_i at equal arguments: series of ln(1 + y)/y in
!     y = (w_i - w_j)/(1 + w_j) below |y| = 1e-3 (five terms, error
!     below 2e-16)
!
      real*8 function hencky_dlog(wi,wj)
      implicit none
      real*8 wi,wj,y,hencky_log1p
      y=(wi-wj)/(1.d0+wj)
      if(dabs(y).lt.1.d-3) then
         hencky_dlog=(1.d0-y*(0.5d0-y*(1.d0/3.d0-y*(0.25d0
     &        -y*0.2d0))))/(1.d0+wj)
      else
         hencky_dlog=(hencky_log1p(wi)-hencky_log1p(wj))/(wi-wj)
      endif
      return
      end
