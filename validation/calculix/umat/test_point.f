!     test_point.f: material-point checks of umat_user.f against
!     closed forms (build.sh runs it; each line prints the worst
!     relative error and PASS/FAIL against its tolerance):
!     1. confined compression, elastic and Maxwell's elastic limit
!        (eta = 1e30 MPa s, dt = 1 s): Cauchy
!        sigma_zz = (lambda + 2 mu) ln(l)/l, sigma_xx = lambda ln(l)/l;
!     2. a general (non-coaxial) F, elastic: E = ln(C)/2 satisfies
!        exp(2E) = C (Taylor series of exp), and S = dW/dE_GL with
!        W = mu |dev E|^2 + kappa tr(E)^2/2 (central differences of
!        W): checks P = dE/dE_GL;
!     3. Maxwell relaxation after a confined compression to l:
!        backward Euler's s_n = s_0/(1 + 2 mu dt/eta)^n to round-off
!        and the exact exp(-2 mu t/eta) to first order in dt;
!     4. Norton-Hoff with m = 1, sY = 0, K = 3 eta/2 equals Maxwell;
!     5. the tangent: symmetric, and equal to a central difference
!        of the stress with a step 100x larger.
!
      program test_point
      implicit none
      integer nfail
      nfail=0
      call t_confined(nfail)
      call t_general(nfail)
      call t_relax(nfail)
      call t_norton(nfail)
      call t_tangent(nfail)
      if(nfail.eq.0) then
         write(*,*) 'all material-point checks passed'
      else
         write(*,*) nfail,' material-point checks FAILED'
         call exit(1)
      endif
      end
!
      subroutine report(name,err,tol,nfail)
      implicit none
      character*(*) name
      real*8 err,tol
      integer nfail
      if(err.le.tol) then
         write(*,'(a,a,es10.3,a,es8.1,a)') name,': ',err,
     &        ' (tol ',tol,') PASS'
      else
         write(*,'(a,a,es10.3,a,es8.1,a)') name,': ',err,
     &        ' (tol ',tol,') FAIL'
         nfail=nfail+1
      endif
      end
!
!     one call of the umat at one point: PK2 s from Lagrange strain el
!
      subroutine point(c,nc,el,ev0,dt,s,ev1,stiff,icmd)
      implicit none
      integer nc,icmd,mi(3),ithermal(2),kode,i,ielas,ipkon(1)
      real*8 c(*),el(6),ev0(6),dt,s(6),ev1(6),stiff(21),xs0(6,1,1),
     &  xs1(6,1,1),em0(6),beta(6),xokl(3,3),xkl(3,3),pg(3),orab(7,1),
     &  pnewdt,t1l,time,ttime,voj,vj
      character*80 amat
      amat='HENCKY'
      kode=-100-nc
      mi(1)=1
      ithermal(1)=0
      ielas=0
      pnewdt=-1.d0
      do i=1,6
         xs0(i,1,1)=ev0(i)
         em0(i)=0.d0
         beta(i)=0.d0
         s(i)=0.d0
      enddo
      call umat_user(amat,1,1,kode,c,el,em0,beta,xokl,voj,xkl,vj,
     &     ithermal,t1l,dt,time,ttime,icmd,ielas,mi,6,xs0,xs1,s,
     &     stiff,0,pg,orab,pnewdt,ipkon)
      if(pnewdt.gt.0.d0) then
         write(*,*) 'umat asked to cut the increment'
         call exit(1)
      endif
      do i=1,6
         ev1(i)=xs1(i,1,1)
      enddo
      end
!
      subroutine t_confined(nfail)
      implicit none
      integer nfail,k
      integer nc
      real*8 c(3),el(6),ev(6),s(6),ev1(6),st(21),l,ls(3),lam,mu,err,
     &  szz,sxx
      data ls /0.97d0,0.9d0,0.7d0/
      c(1)=20000.d0
      c(2)=0.3d0
      c(3)=1.d30
      lam=c(1)*c(2)/((1.d0+c(2))*(1.d0-2.d0*c(2)))
      mu=c(1)/(2.d0*(1.d0+c(2)))
      err=0.d0
      do nc=2,3
      do k=1,3
         l=ls(k)
         el=0.d0
         ev=0.d0
         el(3)=(l*l-1.d0)/2.d0
         call point(c,nc,el,ev,1.d0,s,ev1,st,3)
!        Cauchy: sigma = F S F^T / J, F = diag(1, 1, l), J = l
         szz=l*s(3)
         sxx=s(1)/l
         err=max(err,dabs(szz/((lam+2.d0*mu)*dlog(l)/l)-1.d0))
         err=max(err,dabs(sxx/(lam*dlog(l)/l)-1.d0))
      enddo
      enddo
      call report('confined compression l = 0.97, 0.9, 0.7, elastic '
     &     //'and Maxwell with eta = 1e30',err,
     &     1.d-13,nfail)
      end
!
      subroutine t_general(nfail)
      implicit none
      integer nfail,i,j,k,n,ia(6),ib(6)
      real*8 c(2),f(3,3),cm(3,3),el(6),ev(6),s(6),ev1(6),st(21),
     &  eh(3,3),x(3,3),term(3,3),tmp(3,3),err,w,wp,wm,h,e2(6),
     &  hencky_energy,scale
      data ia /1,2,3,1,1,2/
      data ib /1,2,3,2,3,3/
      c(1)=20000.d0
      c(2)=0.3d0
      f=reshape((/0.83d0,0.21d0,-0.05d0,-0.17d0,1.12d0,0.08d0,
     &     0.04d0,-0.11d0,0.91d0/),(/3,3/))
      cm=matmul(transpose(f),f)
      do i=1,6
         el(i)=cm(ia(i),ib(i))/2.d0
      enddo
      do i=1,3
         el(i)=el(i)-0.5d0
      enddo
      ev=0.d0
!     E through the umat's own routines
      call hencky_point_log(el,eh)
!     exp(2E) by its Taylor series (40 terms)
      x=0.d0
      term=0.d0
      do i=1,3
         x(i,i)=1.d0
         term(i,i)=1.d0
      enddo
      do n=1,40
         tmp=matmul(term,2.d0*eh)/dble(n)
         term=tmp
         x=x+term
      enddo
      err=0.d0
      do i=1,3
         do j=1,3
            err=max(err,dabs(x(i,j)-cm(i,j)))
         enddo
      enddo
      call report('general F: exp(2 ln(C)/2) = C',err,1.d-13,nfail)
!     S against dW/dE_GL
      call point(c,2,el,ev,0.d0,s,ev1,st,3)
      scale=0.d0
      do i=1,6
         scale=max(scale,dabs(s(i)))
      enddo
      err=0.d0
      h=1.d-6
      do k=1,6
         e2=el
         e2(k)=el(k)+h
         wp=hencky_energy(c,e2)
         e2(k)=el(k)-h
         wm=hencky_energy(c,e2)
         w=(wp-wm)/(2.d0*h)
         if(k.gt.3) w=w/2.d0
         err=max(err,dabs(w-s(k))/scale)
      enddo
      call report('general F: S = dW/dE_GL (central differences)',
     &     err,1.d-8,nfail)
      end
!
!     E = ln(C)/2 as a 3x3 matrix from the Lagrange strain el
!
      subroutine hencky_point_log(el,eh)
      implicit none
      integer ierr
      real*8 el(6),eh(3,3),w(3),v(3,3),ep(3),x(6)
      call hencky_principal(el,w,v,ep,x,ierr)
      call hencky_unpack(x,eh)
      end
!
      real*8 function hencky_energy(c,el)
      implicit none
      integer i,j
      real*8 c(2),el(6),eh(3,3),tr,mu,bk,d
      call hencky_point_log(el,eh)
      mu=c(1)/(2.d0*(1.d0+c(2)))
      bk=c(1)/(3.d0*(1.d0-2.d0*c(2)))
      tr=eh(1,1)+eh(2,2)+eh(3,3)
      hencky_energy=bk*tr*tr/2.d0
      do i=1,3
         do j=1,3
            d=eh(i,j)
            if(i.eq.j) d=d-tr/3.d0
            hencky_energy=hencky_energy+mu*d*d
         enddo
      enddo
      end
!
      subroutine t_relax(nfail)
      implicit none
      integer nfail,n,k,nsteps(2)
      real*8 c(3),el(6),ev(6),s(6),ev1(6),st(21),l,mu,bk,dt,tau,err,
     &  tzz,txx,sd0,sdn,t,errx(2),p
      data nsteps /200,400/
      c(1)=20000.d0
      c(2)=0.3d0
      c(3)=30000.d0
      mu=c(1)/(2.d0*(1.d0+c(2)))
      bk=c(1)/(3.d0*(1.d0-2.d0*c(2)))
      l=0.9d0
      tau=c(3)/(2.d0*mu)
      err=0.d0
      do k=1,2
         errx(k)=0.d0
         dt=1.d0/dble(nsteps(k))
         el=0.d0
         el(3)=(l*l-1.d0)/2.d0
         ev=0.d0
!        the jump at t = 0 in an increment of 1e-12 s, then the hold
         call point(c,3,el,ev,1.d-12,s,ev1,st,3)
         ev=ev1
         sd0=2.d0*mu*dlog(l)*2.d0/3.d0
         p=bk*dlog(l)
         do n=1,nsteps(k)
            call point(c,3,el,ev,dt,s,ev1,st,3)
            ev=ev1
!           T = C S C for this diagonal C: T_zz = l^2 S_zz
            tzz=l*l*s(3)
            txx=s(1)
            t=n*dt
            sdn=sd0/(1.d0+2.d0*mu*dt/c(3))**n
            err=max(err,dabs(tzz-(p+sdn))/dabs(p+sd0))
            err=max(err,dabs(txx-(p-sdn/2.d0))/dabs(p+sd0))
            errx(k)=max(errx(k),dabs(tzz-(p+sd0*dexp(-t/tau)))
     &           /dabs(sd0))
         enddo
      enddo
      call report('Maxwell relaxation vs backward Euler closed form',
     &     err,1.d-12,nfail)
      write(*,'(a,2es10.3,a,f6.3)')
     &     'Maxwell relaxation vs exp(-t/tau), dt = 1/200, 1/400 s: ',
     &     errx(1),errx(2),'  ratio ',errx(1)/errx(2)
      call report('  first order in dt (ratio - 2)',
     &     dabs(errx(1)/errx(2)-2.d0),0.05d0,nfail)
      end
!
      subroutine t_norton(nfail)
      implicit none
      integer nfail,n
      real*8 cm(3),cn(5),el(6),evm(6),evn(6),sm(6),sn(6),ev1(6),
     &  st(21),err,scale
      cm(1)=20000.d0
      cm(2)=0.3d0
      cm(3)=30000.d0
      cn(1)=cm(1)
      cn(2)=cm(2)
      cn(3)=1.5d0*cm(3)
      cn(4)=1.d0
      cn(5)=0.d0
      evm=0.d0
      evn=0.d0
      err=0.d0
      do n=1,50
         el=0.d0
         el(3)=-0.002d0*n
         el(4)=0.0007d0*n
         el(1)=0.0003d0*n
         call point(cm,3,el,evm,0.02d0,sm,ev1,st,3)
         evm=ev1
         call point(cn,5,el,evn,0.02d0,sn,ev1,st,3)
         evn=ev1
         scale=maxval(dabs(sm))
         err=max(err,maxval(dabs(sm-sn))/scale)
      enddo
      call report('Norton-Hoff (m = 1, sY = 0, K = 3 eta/2) = Maxwell',
     &     err,1.d-12,nfail)
      end
!
      subroutine t_tangent(nfail)
      implicit none
      integer nfail,i,k,kel(4,21),ip(3,3),a,b
      real*8 c(5),el(6),ev(6),s(6),ev1(6),st(21),sp(6),sm(6),e2(6),
     &  h,cc(6,6),err,scale
      kel=reshape((/1,1,1,1,1,1,2,2,2,2,2,2,1,1,3,3,2,2,3,3,3,3,3,3,
     &          1,1,1,2,2,2,1,2,3,3,1,2,1,2,1,2,1,1,1,3,2,2,1,3,
     &          3,3,1,3,1,2,1,3,1,3,1,3,1,1,2,3,2,2,2,3,3,3,2,3,
     &          1,2,2,3,1,3,2,3,2,3,2,3/),(/4,21/))
      ip=reshape((/1,4,5,4,2,6,5,6,3/),(/3,3/))
      c(1)=20000.d0
      c(2)=0.3d0
      c(3)=200.d0
      c(4)=3.d0
      c(5)=20.d0
      el=(/-0.08d0,0.05d0,0.02d0,0.03d0,-0.01d0,0.015d0/)
      ev=(/0.001d0,-0.002d0,0.001d0,0.0005d0,0.d0,-0.0003d0/)
      call point(c,5,el,ev,0.01d0,s,ev1,st,1)
      h=1.d-5
      do k=1,6
         e2=el
         e2(k)=el(k)+h
         call point(c,5,e2,ev,0.01d0,sp,ev1,st,3)
         e2(k)=el(k)-h
         call point(c,5,e2,ev,0.01d0,sm,ev1,st,3)
         do i=1,6
            cc(i,k)=(sp(i)-sm(i))/(2.d0*h)
            if(k.gt.3) cc(i,k)=cc(i,k)/2.d0
         enddo
      enddo
      call point(c,5,el,ev,0.01d0,s,ev1,st,1)
      scale=maxval(dabs(cc))
      err=0.d0
      do k=1,21
         a=ip(kel(1,k),kel(2,k))
         b=ip(kel(3,k),kel(4,k))
         err=max(err,dabs(st(k)-cc(a,b))/scale)
      enddo
      call report('tangent (Norton-Hoff, flowing) vs step 1e-5',err,
     &     1.d-6,nfail)
      end
